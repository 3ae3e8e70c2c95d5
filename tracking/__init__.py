"""swarmdeck.tracking"""
