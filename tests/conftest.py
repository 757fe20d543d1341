import numpy as np
import pytest

from eqrec.core.acc import acc_system

L1 = ["101111", "110111", "111011", "111101"]


@pytest.fixture(scope="session")
def acc():
    return acc_system()


@pytest.fixture(scope="session")
def L1_words():
    return list(L1)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
