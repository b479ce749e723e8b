"""Into how few columns can the left path take its small step (P1)?

Usage: ``python docs/sgm/p1_columns_study.py --dataset DIR --out
docs/sgm/p1_columns_study.json`` (DIR: the Middlebury 2003 teddy folder), then ``--report``.

The golden model's left path takes the P1 transitions into odd columns only, so that its
loop closes over two positions (docs/sgm.md, "Two clocks at R = 1"). With them into one
column in P, the loop would close over P positions: the P - 1 columns without them are
per lane a minimum of two (Lu(x - 1, d) and the large step) and need no neighbour. This
study measures what fewer P1 columns cost, everything else the golden model's (tracked
reference J = 8, K = 32; the three paths from the row above golden/sgm.py's), with
``left_path_study``'s conditions and metric; the rows are exact SGM's left path, the golden
model's (P = 2, checked bit for bit there), P = 3 and 4, and none at all.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from left_path_study import measure, report, study_main  # noqa: E402

from npstereo.params import SGM_TRACK_AGE, SGM_TRACK_STEPS  # noqa: E402

_TRACKED = (1, "track", SGM_TRACK_STEPS, SGM_TRACK_AGE)
#: (name, step, kind, J, K, (period, phase) or None): ``left_path_study``'s variants.
#: "none" is a period no column reaches.
VARIANTS = [("exact", 1, "exact", 0, 0),
            ("P1 into one column in 2 (golden)", *_TRACKED, (2, 1)),
            ("P1 into one column in 3", *_TRACKED, (3, 2)),
            ("P1 into one column in 4", *_TRACKED, (4, 3)),
            ("P1 into no column", *_TRACKED, (1, 1))]


def main(argv=None):
    return study_main(argv, __doc__.splitlines()[0],
                      lambda dataset, config: measure(dataset, config, VARIANTS), report)


if __name__ == "__main__":
    sys.exit(main())
