"""``npstereo board``: a stereo core on an FPGA board, showing its colour-mapped disparity
map on the board's video output (docs/board.md).

:mod:`.video` (timings, placement, the expected frame), :mod:`.display` (the design up to
the TMDS encoders), :mod:`.tmds` (encoders and serialisers), :mod:`.ulx3s` (the ULX3S
top: PLL, resets, HDMI pins), :mod:`.verify` (the board top simulated against the golden
model), :mod:`.flow` (Yosys, nextpnr-ecp5, ecppack) and :mod:`.fit` (what fits the board).
"""
