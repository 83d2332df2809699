"""Assertions shared by the collision tests."""

import numpy as np
import pytest

from surfeledit.errors import InvalidArgumentError


def assert_rejected_and_inert(backend, bad, field):
    """``backend.configure(**bad)`` raises InvalidArgumentError naming ``field``, and the session's
    settings, built structures and colliding set are exactly as before."""
    before = backend.session.settings()
    structures = backend.session.report()["structures"]
    colliding = np.asarray(backend.session.colliding()).copy()
    with pytest.raises(InvalidArgumentError) as e:
        backend.configure(**bad)
    assert e.value.field == field, str(e.value)
    assert backend.session.settings() == before
    assert backend.session.report()["structures"] == structures
    assert np.array_equal(np.asarray(backend.session.colliding()), colliding)
