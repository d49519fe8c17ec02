#!/usr/bin/env python3
"""Prints the name of the run under DIR with the lowest validation ANLL of the prior (eval.json
"val" block): hyper-parameters are chosen on validation windows, never on the test split."""
import json
import pathlib
import sys

best = None
for ev in sorted(pathlib.Path(sys.argv[1]).glob("*/eval.json")):
    anll = json.loads(ev.read_text())["val"]["prior"]["anll"]
    if anll is not None and (best is None or anll < best[0]):
        best = (anll, ev.parent.name)
if best is None:
    sys.exit(f"no run with a validation ANLL under {sys.argv[1]}")
print(best[1])
