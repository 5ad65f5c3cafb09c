"""Each study's test module names its study (NAME); the study runs once per module."""

import pytest
from study_runner import run_quick


@pytest.fixture(scope="module")
def out(request, tmp_path_factory):
    return tmp_path_factory.mktemp(request.module.NAME)


@pytest.fixture(scope="module")
def results(request, out):
    return run_quick(request.module.NAME, out)
