"""npstereo gen"""
