"""A report that fits in one page stays the page it was: the published map's report (no
traces) and a reduced campaign's (traces, overlays) are compared with the pages the code
wrote before a report's tables could lie beside it (``tests/data/report_inline/``), byte
for byte once the time stamp and the PNGs (matplotlib's bytes) are set aside.

To rewrite the kept pages after a deliberate change of the one-page report:
``PYTHONPATH=src python tests/test_report_pages.py --update`` (then read the diff).
"""

from __future__ import annotations

import gzip
import re
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from published_map import PUBLISHED_CSV, write_published_map  # noqa: E402
from reduced_runs import make_processed  # noqa: E402
from tribopipe.report import build_report, report_inputs  # noqa: E402

KEPT = Path(__file__).resolve().parent / "data" / "report_inline"
STAMP = re.compile(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC")
PNG = re.compile(r"data:image/png;base64,[A-Za-z0-9+/=]+")


def normalised(html: str, root: Path) -> str:
    """``html`` with its time stamp, its PNGs and the temporary folder ``root`` replaced
    by fixed words (what differs between two runs of the same code)."""
    return PNG.sub("PNG", STAMP.sub("STAMP", html)).replace(str(root), "ROOT")


def one_page_reports(root: Path) -> dict[str, str]:
    """The two one-page reports, normalised: the published map's and a campaign's."""
    published = write_published_map(PUBLISHED_CSV, root / "friction_map.parquet")
    map_path, processed = make_processed(root / "c")
    return {
        "published": normalised(build_report(report_inputs(published, source="published")),
                                root),
        "campaign": normalised(build_report(report_inputs(map_path, processed,
                                                          source="campaign")), root),
    }


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[str, str]:
    return one_page_reports(tmp_path_factory.mktemp("pages"))


@pytest.mark.parametrize("name", ["published", "campaign"])
def test_a_one_page_report_is_byte_for_byte_the_page_it_was(pages, name):
    kept = gzip.decompress((KEPT / f"{name}.html.gz").read_bytes()).decode("utf-8")
    page = pages[name]
    assert "data-runs=" not in page and "report_runs" not in page
    assert page == kept


if __name__ == "__main__" and sys.argv[1:] == ["--update"]:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        for name, text in one_page_reports(Path(tmp)).items():
            (KEPT / f"{name}.html.gz").write_bytes(gzip.compress(text.encode("utf-8"),
                                                                 mtime=0))
            print(f"wrote {KEPT / name}.html.gz")
