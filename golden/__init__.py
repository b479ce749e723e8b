"""npstereo golden"""
