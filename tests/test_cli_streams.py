"""The command's streams: a warning is said once per command, however often it is raised."""

import warnings

from magdesign._cli_streams import show_warnings_once
from magdesign.spec.checks import PlausibilityWarning


def test_a_warning_is_said_once_per_command_even_across_catch_warnings(capsys):
    show = show_warnings_once()
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = show
        for message in ("load.normal: a", "load.normal: a", "sensor.map_grid: b", "load.normal: a"):
            warnings.warn(message, PlausibilityWarning, stacklevel=1)
    assert capsys.readouterr().err == "magdesign: warning: load.normal: a\nmagdesign: warning: sensor.map_grid: b\n"
    fresh = show_warnings_once()  # the next command says it again
    fresh(PlausibilityWarning("load.normal: a"), PlausibilityWarning, __file__, 1)
    assert capsys.readouterr().err == "magdesign: warning: load.normal: a\n"
