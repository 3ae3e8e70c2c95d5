"""The projector output (issue 29): the fifth renderer of the picture, drawn on the floor by an overhead projector.

``message`` turns a Frame's picture into the layers the operator chose (JSON); ``server`` serves the full-screen
page (``static/projector.html`` + ``projector.js``: a canvas in floor metres warped by the floor → projector
homography with a CSS ``matrix3d``) and streams the newest Frame to every page. The homography comes from
``swarmdeck calibrate projector`` (:mod:`swarmdeck.tracking.projector`).
"""
