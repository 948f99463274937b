"""Helper of test_orbits_neighbour: one Radau pass (variational, then chord) without numba.

Usage: python _plain_flow.py IN.npz OUT.npz (u, T, n, steps in; y, monodromy, sensitivity,
and the chord pass's y out)."""

import sys


def main() -> None:
    sys.modules["numba"] = None  # as if numba were not installed: the kernels run as plain Python
    import numpy as np

    import flutterswim as fs
    from flutterswim import _jit
    from flutterswim.orbits.shooting import flow
    from flutterswim.orbits.system import ShapeSystem

    assert not _jit.have_numba()
    d = np.load(sys.argv[1])
    s = ShapeSystem.of(fs.PAPER.groups, int(d["n"]))
    f0 = flow(s, d["u"], float(d["T"]), int(d["steps"]), variational=True, sensitivity=True)
    f1 = flow(s, d["u"], float(d["T"]), int(d["steps"]), warm=f0)  # the chord pass
    np.savez(sys.argv[2], y=f0.y, mono=f0.monodromy, sens=f0.sensitivity, y1=f1.y)


if __name__ == "__main__":
    main()
