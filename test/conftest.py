"""Shared test set-up. Tests that need the real data sets use the `data_dir` fixture, which
skips them (with the reason) when ../shared/data is absent."""
import os
import random
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("SPATIAL_GROUNDING_DATA", REPO.parent / "shared" / "data"))

# Real DDS on loopback only, in a domain of this run's own, so parallel runs never meet.
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("ROS_DOMAIN_ID", str(random.Random(os.getpid()).randint(1, 100)))


@pytest.fixture(scope="session")
def data_dir() -> Path:
    if not (DATA / "puddleworld" / "local.p").is_file():
        pytest.skip(f"real data sets not found at {DATA} (set SPATIAL_GROUNDING_DATA)")
    return DATA
