"""swarmdeck.inputs"""
