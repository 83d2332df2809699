"""Python tests against real surfeledit-server processes (see conftest.py)."""
