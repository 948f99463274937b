"""Run every benchmark script in this folder, one after the other, with one BLAS thread."""

import os
import subprocess
import sys
from pathlib import Path

here = Path(__file__).parent
env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
failed = []
for script in sorted(here.glob("bench_*.py")):
    print(f"=== {script.name}", flush=True)
    if subprocess.run([sys.executable, str(script)], env=env).returncode != 0:
        failed.append(script.name)
if failed:
    sys.exit(f"failed: {', '.join(failed)}")
