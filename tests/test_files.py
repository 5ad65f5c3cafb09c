"""Files are written whole or not at all (magdesign._files.replaced)."""

import pytest

from magdesign._files import replaced


def test_a_file_is_replaced_whole_and_a_failure_leaves_the_old_one(tmp_path):
    path = tmp_path / "design.csv"
    path.write_text("old\n")
    with pytest.raises(KeyboardInterrupt), replaced(path) as temporary:
        assert temporary.parent == tmp_path and temporary.suffix == ".csv" and temporary != path
        temporary.write_text("half")
        raise KeyboardInterrupt
    assert path.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.csv"]  # no temporary left
    with replaced(path) as temporary:
        temporary.write_text("new\n")
    assert path.read_text() == "new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.csv"]
