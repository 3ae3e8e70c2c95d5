"""swarmdeck.coverage"""
