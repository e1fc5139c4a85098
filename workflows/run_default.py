#!/usr/bin/python3
"""The README's main command: btr settle (BTR -> calibration pour -> LIGGGHTS relaxation) -> comparison -> report on the default
scene inputs/bed3d.toml, into out/bed3d/. Extra arguments go to `btr_workflow.py pipeline`
(e.g. --np 2, --count 2000)."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import btr_workflow  # noqa: E402

if __name__ == "__main__":
    btr_workflow.stop_on_signals()
    sys.exit(btr_workflow.main(["pipeline", str(btr_workflow.DEFAULT_SCENE), "--engine", "liggghts"] + sys.argv[1:]))
