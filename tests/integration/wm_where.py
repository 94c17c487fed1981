"""Prints where each product of a finished run's world model is (read back from the
world model server's journal in RUN_DIR/wm), as JSON. Runs inside the test's sandbox."""

import json
import sys
from pathlib import Path

from skillbus.demo import world_model_after

print(json.dumps(world_model_after(Path(sys.argv[1]))), flush=True)
