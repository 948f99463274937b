"""Every numeric global attribute of a branch file carries its units (a review: the Hopf
point's value, the Lyapunov coefficient and its slope, the steps and the range had none)."""

import numpy as np
import xarray as xr

from flutterswim.cli import main


def test_a_branch_files_numeric_attributes_have_units(tmp_path):
    out = tmp_path / "b.nc"
    assert main(["branch", "kappa_E_ratio=1:1.5", "--points", "4", "--segments", "12", "--quiet",
                 "--look-beyond", "0", "--out", str(out)]) == 0
    attrs = xr.open_dataset(out, engine="h5netcdf").attrs
    numeric = [k for k, v in attrs.items() if isinstance(v, (int, float, np.integer, np.floating))
               and not k.startswith("n_")]  # (counts: n_segments, n_inaccurate_orbits)
    assert numeric
    missing = [k for k in numeric if f"{k}_units" not in attrs]
    assert missing == []
    assert attrs["lyapunov_coefficient_units"] == "1" and attrs["lyapunov_coefficient_scaled_units"] == "1/tau"
