"""swarmdeck.safety"""
