"""Shared test fixtures.

``shared_dir`` points at the project's read-only real-world material (``../shared``): the
founding paper's ``FrictionMap.mat`` and real instrument exports that may not be copied. It
exists in CI and on the developers' machines, not on a user's clone, so tests that need it
skip with a reason when it is absent. Files whose licence allows it are copied into
``tests/data/`` (see its README); the published map's CSV ships with the package and is
read from there (``published_map.PUBLISHED_CSV``).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    import pandas as pd

REPO = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
SHARED = Path(os.environ.get("TRIBOPIPE_SHARED", REPO.parent / "shared"))


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """``tests/data``: small real files we may ship, with their licence notices."""
    return DATA


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """``../shared``; skips the test when it is absent (e.g. on a user's clone)."""
    if not SHARED.is_dir():
        pytest.skip(f"../shared not found at {SHARED} (only in CI and on developer machines)")
    return SHARED


def shared_file(*parts: str) -> Path:
    """A file under ``../shared``; skips the calling test when it is absent."""
    path = SHARED.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"{path} not found (../shared exists only in CI and on developer machines)")
    return path


@pytest.fixture(autouse=True)
def _no_project_file() -> Iterator[None]:
    """Each test starts without ``./.tribopipe-map`` (the map commands read without
    ``--map``, written by ``batch``) and leaves the one it found, if any, as it was: a
    ``make demo`` before ``make test`` or a batch run by a test never steers another
    test's map."""
    project = Path.cwd() / ".tribopipe-map"
    kept = project.read_bytes() if project.is_file() else None
    project.unlink(missing_ok=True)
    try:
        yield
    finally:
        project.unlink(missing_ok=True)
        if kept is not None:
            project.write_bytes(kept)


@pytest.fixture(scope="session")
def published_runs() -> pd.DataFrame:
    """The founding paper's published map (shipped CSV) as map rows. Read-only: a test
    that changes it works on a copy."""
    from published_map import PUBLISHED_CSV
    from published_map import published_runs as runs_of

    return runs_of(PUBLISHED_CSV)


@pytest.fixture(scope="session")
def published_groups(published_runs: pd.DataFrame) -> pd.DataFrame:
    """The group table (``query.group_table``) of :func:`published_runs`. Read-only: a
    test that changes it works on a copy."""
    from published_map import group_table

    return group_table(published_runs)


@pytest.fixture(scope="session")
def runs(published_runs: pd.DataFrame) -> pd.DataFrame:
    """:func:`published_runs`, the map rows most tests read (a module may define its own)."""
    return published_runs


@pytest.fixture(scope="session")
def groups(published_groups: pd.DataFrame) -> pd.DataFrame:
    """:func:`published_groups`, the groups most tests query (a module may define its own,
    e.g. with a μ_S: :func:`helpers.with_mu_s`)."""
    return published_groups


# ------------------------------------------------------------------ one browser per session
# Playwright's sync API runs one driver per thread: every browser test of a session shares
# this one (the explorer's, the review page's).

CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
]


def browser_unavailable(reason: str) -> None:
    """Skip the calling test with ``reason``; a failure where TRIBOPIPE_REQUIRE_BROWSER=1
    (CI, where a browser test must run)."""
    if os.environ.get("TRIBOPIPE_REQUIRE_BROWSER") == "1":
        pytest.fail(f"TRIBOPIPE_REQUIRE_BROWSER=1 but {reason}")
    pytest.skip(reason)


def chromium_executable() -> str:
    """The system's Chromium (or TRIBOPIPE_CHROMIUM), once Playwright is known to be
    importable; :func:`browser_unavailable` when either is missing."""
    executable = os.environ.get("TRIBOPIPE_CHROMIUM") or shutil.which("chromium")
    if not executable:
        browser_unavailable("no chromium on PATH (Debian: apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        browser_unavailable("playwright is not installed (pip install -e '.[test]')")
    return str(executable)


@pytest.fixture(scope="session")
def browser():
    """A headless Chromium (the system's ``chromium``) under Playwright."""
    executable = chromium_executable()
    from playwright.sync_api import sync_playwright

    manager = sync_playwright().start()
    try:
        instance = manager.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
    except Exception as exc:  # the browser exists but cannot start here
        manager.stop()
        browser_unavailable(f"chromium at {executable} did not start: "
                            f"{str(exc).splitlines()[0]}")
    yield instance
    instance.close()
    manager.stop()
