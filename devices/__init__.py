"""swarmdeck.devices"""
