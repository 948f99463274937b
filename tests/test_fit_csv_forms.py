"""The trials CSV as spreadsheets write it: a byte-order mark, spaces after the commas; and
the forms it may not take, each named: another separator, names with units, a voltage of 0."""

import numpy as np
import pytest

from flutterswim._validate import ParameterError
from flutterswim.fitting.data import read_trials

ROWS = ["85,1,0.377,0.394,1.13", "85,2,0.380,0.390,1.12", "80,1,0.390,0.380,1.10"]
HEADER = "voltage_V,sample,period_s,advance_mm,lateral_mm"


def _write(path, header, rows, encoding="utf-8", sep=","):
    path.write_text("\n".join([header.replace(",", sep)] + [r.replace(",", sep) for r in rows]) + "\n",
                    encoding=encoding)
    return path


def test_a_byte_order_mark_and_padded_names_read_as_the_plain_file(tmp_path):
    plain = read_trials(_write(tmp_path / "a.csv", HEADER, ROWS))
    bom = read_trials(_write(tmp_path / "b.csv", HEADER, ROWS, encoding="utf-8-sig"))
    padded = read_trials(_write(tmp_path / "c.csv", HEADER.replace(",", ", "), ROWS))
    for other in (bom, padded):
        np.testing.assert_array_equal(other.values, plain.values)
        np.testing.assert_array_equal(other.voltage_V, plain.voltage_V)


def test_other_forms_are_refused_naming_what_is_wrong(tmp_path):
    with pytest.raises(ParameterError, match="separated by ';'"):
        read_trials(_write(tmp_path / "s.csv", HEADER, ROWS, sep=";"))
    with pytest.raises(ParameterError, match=r"its header has 'voltage \[V\]'"):
        read_trials(_write(tmp_path / "u.csv", "voltage [V],sample,period [s],advance [mm],lateral [mm]", ROWS))
    with pytest.raises(ParameterError, match="voltage_V='0' is not allowed"):
        read_trials(_write(tmp_path / "z.csv", HEADER, ["0,1,0.377,0.394,1.13"] + ROWS))
