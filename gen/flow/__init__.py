"""Synthesis: Yosys and nextpnr driven on generated Verilog, and what is read from them.

:func:`.synthesise.synthesise` is the flow (``docs/synthesis-flow.md``); the modules
beside it each do one job of it: finding the tools (:mod:`.tools`), running one in a
process group with a deadline (:mod:`.processes`), the Yosys script (:mod:`.yosys`, in
native Yosys through :mod:`.yosys_worker`), the figures read from what the tools write
(:mod:`.logs`), place and route (:mod:`.nextpnr`), the ECP5 block-RAM output registers
(:mod:`.bram_output_register`), the logic depth (:mod:`.logic_depth`) and the devices'
capacities (:mod:`.capacity`).
"""
