"""pytest fixtures for integration tests against a real manipid server.

Enable in a conftest.py (or test module) with

    pytest_plugins = ["manipid_client.pytest_plugin"]

Fixtures: `manipid_server` (session scope: the URL of one `manipid serve` on a temporary
database, a ServerURL str) and `manipid_client` (a Client for it). The binary is found as
local_server() finds it; `pytest --manipid-bin=PATH` overrides (with `=`: the
option is read before conftest plugins load). Only this module imports
pytest, so the package itself never needs it.
"""
from __future__ import annotations

from typing import Iterator

import pytest

from .client import Client
from .server import ServerURL, local_server


def pytest_addoption(parser: "pytest.Parser") -> None:
    parser.addoption("--manipid-bin", default=None,
                     help="--manipid-bin=PATH: the manipid executable for the manipid_server fixture (default: MANIPID_BIN, PATH, build/)")


@pytest.fixture(scope="session")
def manipid_server(request: "pytest.FixtureRequest") -> Iterator[ServerURL]:
    """One `manipid serve --port 0` for the test session, on a temporary database."""
    with local_server(binary=request.config.getoption("--manipid-bin")) as url:
        yield url


@pytest.fixture
def manipid_client(manipid_server: ServerURL) -> Client:
    """A Client connected to the session's server."""
    return Client(manipid_server)
