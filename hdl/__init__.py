"""npstereo hdl"""
