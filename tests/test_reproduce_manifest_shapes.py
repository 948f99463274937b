"""A reproduce folder's manifest edited into another shape is read as unreadable (every target
reruns), not a TypeError (a review: "targets": NaN made `reproduce --only table1` exit 1)."""

import json

import pytest

from flutterswim.reproduce.manifest import MANIFEST_NAME, Manifest


@pytest.mark.parametrize("text", ['{"targets": NaN}', '[1, 2]', '{"targets": [1], "run": 3}',
                                  '{"targets": {"table1": 5, "fig3": {"key": "k", "status": "ok", "outputs": 7}}}'])
def test_a_manifest_of_another_shape_reruns_its_targets(tmp_path, text):
    (tmp_path / MANIFEST_NAME).write_text(text)
    man = Manifest.load(tmp_path)
    assert isinstance(man.targets, dict) and isinstance(man.run, dict)
    for name in ("table1", "fig3"):
        assert man.up_to_date(name, "k") is False
    man.record("table1", {"status": "ok", "key": "k2"})  # and it is written again, as JSON
    assert json.loads((tmp_path / MANIFEST_NAME).read_text())["targets"]["table1"]["key"] == "k2"
