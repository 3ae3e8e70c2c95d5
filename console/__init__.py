"""swarmdeck.console: the control loop, the browser console (viser), recording/playback and the CLI.

Public API (import from the submodules; this package imports nothing so the CLI starts fast):

* :mod:`swarmdeck.console.runtime.frame` — ``Frame`` (one immutable record per control tick, the
  recording format: ``to_dict`` / ``from_dict``), ``BarrierFrame``, ``CoverageFrame``, ``ContactsFrame``.
* :mod:`swarmdeck.console.runtime.loop` — ``ControlLoop`` (sense → inputs → control → safety+actuation → send →
  Frame; ``tick()`` on a virtual clock or ``start()`` on its own thread), ``LoopConfig``,
  ``SafetyParams``, ``DensityParams``.
* :mod:`swarmdeck.console.runtime.behaviours` — coverage, rendezvous, formation, goto, ``script:PATH``.
* :mod:`swarmdeck.console.runtime.hardware` — the robot ports (:mod:`swarmdeck.core.ports`: ``PoseSource``,
  ``CommandSink``, ``SensedPoses``) for camera tracking and MQTT robots; the simulation's is
  ``swarmdeck.devices.simulated_robots.SimulatedRobots``.
* :mod:`swarmdeck.console.web.scene` — ``ArenaScene.draw(frame)``: the viser scene as a function of Frames.
* :mod:`swarmdeck.console.web.gui`, :mod:`swarmdeck.console.web.app` — the control panel and ``ConsoleApp``.
* :mod:`swarmdeck.console.web.plots` — the Plots panel, one drawing code for live and playback
  (:mod:`swarmdeck.console.web.player`).
* ``swarmdeck console`` (:mod:`swarmdeck.console.cli.console`) starts it all.
"""
