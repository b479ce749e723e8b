"""npstereo gen.ip: a core as a package for FuseSoC, IP-XACT and Platform Designer."""
