"""swarmdeck.console"""
