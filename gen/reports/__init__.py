"""Reports: the result cache, the synthesis report of a configuration, the tables and
plots the commands write, and the paper's figures they are put beside."""
