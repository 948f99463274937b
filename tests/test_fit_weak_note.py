"""A fit whose data leave a combination nearly free says so, naming it (the three descriptors
can even be matched exactly at two points of the paper's box); a well determined fit says
nothing. On the scaling surrogate: the same fit at large and at small standard errors."""

import json

import numpy as np

import flutterswim as fs
from flutterswim.fitting import fit, to_identifiable
from flutterswim.fitting.fit import WEAK_SIGMA_REL
from flutterswim.fitting.surrogate import ScalingSurrogate


def test_the_weakly_determined_combination_is_named(tmp_path):
    sur = ScalingSurrogate(fs.PAPER)
    y = sur(to_identifiable(fs.PAPER, 1.94e-14, 0.375, 19.1e3))
    loose = fit(y, 0.2 * y, model=sur)
    assert loose.converged and loose.sigma_rel.max() > WEAK_SIGMA_REL
    note = loose.weakly_determined
    assert "poorly" in note and "--profiles" in note
    # the combination named is the card's weakest one
    a = loose.card.weakest / loose.card.weakest[np.argmax(np.abs(loose.card.weakest))]
    assert f"B^{a[0]:+.2f}" in note
    loose.save(tmp_path / "f.json")
    assert json.loads((tmp_path / "f.json").read_text())["identifiability"]["note"] == note
    tight = fit(y, 1e-3 * y, model=sur)
    assert tight.converged and tight.sigma_rel.max() < WEAK_SIGMA_REL and tight.weakly_determined == ""
