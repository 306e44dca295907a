import pytest

from .support import Chip


@pytest.fixture
def chip() -> Chip:
    return Chip()
