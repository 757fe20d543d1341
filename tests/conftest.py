import os

# The BLAS kernels of the workflow (Snakefile): set before numpy loads OpenBLAS, so that recomputed results equal
# the stored ones on any x86-64 machine.
os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as the Snakefile: results independent of the core count

import numpy as np
import pytest

from pathlib import Path

from eqrec.systems.examples import acc_system
from eqrec.studies.claims.published import published_value

#: The one file of published values; tests that compare with a paper's number read it here.
CLAIMS_FILE = Path(__file__).resolve().parents[1] / "config" / "claims.yaml"

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


@pytest.fixture(scope="session")
def published():
    """``published(claim_id)``: the paper's value of a claim, as a float or an array (config/claims.yaml)."""

    def value(claim_id: str):
        v = published_value(CLAIMS_FILE, claim_id)
        return float(v) if isinstance(v, (str, int, float)) else np.asarray(v, float)

    return value
