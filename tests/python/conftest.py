# SPDX-License-Identifier: MIT
# pytest setup of the isokit module's tests (CTest label python; docs/python.md).
import os

import pytest


@pytest.fixture
def source_dir():
    """tests/ of the source tree (test data)."""
    return os.environ.get("ISOKIT_TEST_SOURCE_DIR", os.path.dirname(os.path.dirname(__file__)))


def pytest_configure(config):
    # Debian's tornado 6.2 under distributed 2022.12 warns about its own event-loop setup.
    config.addinivalue_line("filterwarnings", "ignore:make_current is deprecated:DeprecationWarning")
