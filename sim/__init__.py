"""npstereo sim"""
