"""The package profile has a version and a JSON Schema per version, published in every
package and in docs/package-profile/; readers take every older version we have written
(the v1 and v3 maps and the v3 package of tests/data) and say that they upgraded it."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import jsonschema
import pytest
from click.testing import CliRunner

from reduced_runs import make_processed
from tribopipe.cli import main
from tribopipe.frictionmap.package import check_package
from tribopipe.frictionmap.profile import (
    PROFILE_NAME,
    PROFILE_VERSION,
    PROFILE_VERSIONS,
    profile_schema,
    schema_file,
)
from tribopipe.frictionmap.schema import SCHEMA_VERSION

REPO = Path(__file__).resolve().parents[1]
DATA = Path(__file__).parent / "data"


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def package(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("profile")
    map_path, _ = make_processed(root)
    result = invoke("map", "publish", "-o", root / "pkg", "--lab", "Lab P", "--map", map_path)
    assert result.exit_code == 0, result.output
    return root / "pkg"


@pytest.mark.parametrize("version", sorted(PROFILE_VERSIONS))
def test_the_docs_publish_each_version_s_schema(version):
    published = REPO / "docs" / "package-profile" / f"package-v{version}.schema.json"
    assert json.loads(published.read_text(encoding="utf-8")) == profile_schema(version)
    jsonschema.Draft202012Validator.check_schema(profile_schema(version))


def test_a_package_names_its_profile_and_carries_its_schema(package):
    descriptor = json.loads((package / "datapackage.json").read_text(encoding="utf-8"))
    block = descriptor["tribopipe"]
    assert (block["profile"], block["profile_version"]) == (PROFILE_NAME, PROFILE_VERSION)
    carried = json.loads((package / schema_file()).read_text(encoding="utf-8"))
    assert carried == profile_schema(PROFILE_VERSION)
    jsonschema.validate(descriptor, carried)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(descriptor, profile_schema(1))


def test_the_version_3_package_is_profile_1_and_read_so():
    descriptor = json.loads((DATA / "package_v3/datapackage.json").read_text(encoding="utf-8"))
    jsonschema.validate(descriptor, profile_schema(1))
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(descriptor, profile_schema(PROFILE_VERSION))
    check = check_package(DATA / "package_v3")
    assert check.ok and check.profile_version == 1
    result = invoke("map", "validate", DATA / "package_v3")
    assert result.exit_code == 0
    assert result.output.splitlines()[0].startswith(
        "note: package profile version 1 (summary rows only")
    assert f"read as version {PROFILE_VERSION}" in result.output
    again = invoke("map", "validate", "--recompute", DATA / "package_v3")
    assert again.exit_code == 0, again.output
    assert "2 runs carry no evidence (no trace or raw export in the package)" in again.output


@pytest.mark.parametrize("name,version", [("friction_map_v1.parquet", 1),
                                          ("frictionmap_v1.parquet", 1),
                                          ("friction_map_v3.parquet", 3)])
def test_old_maps_read_and_say_they_were_upgraded(name, version):
    result = invoke("map", "validate", DATA / name)
    assert result.exit_code == 0, result.output
    first = result.output.splitlines()[0]
    assert first.startswith(f"note: friction map schema version {version}, read as version "
                            f"{SCHEMA_VERSION}")


def test_a_newer_profile_is_refused_in_one_line(package, tmp_path):
    target = tmp_path / "pkg"
    shutil.copytree(package, target)
    data = json.loads((target / "datapackage.json").read_text(encoding="utf-8"))
    data["tribopipe"]["profile_version"] = PROFILE_VERSION + 1
    (target / "datapackage.json").write_text(json.dumps(data), encoding="utf-8")
    result = invoke("map", "validate", target)
    assert result.exit_code == 1
    assert (f"package profile version {PROFILE_VERSION + 1}; this tribopipe reads versions 1 "
            f"to {PROFILE_VERSION} (upgrade tribopipe") in result.output
    data["tribopipe"]["profile"] = "something else"
    (target / "datapackage.json").write_text(json.dumps(data), encoding="utf-8")
    assert "expected 'tribopipe-friction-map-package'" in invoke("map", "validate",
                                                                target).output


def test_the_carried_schema_is_checked_like_every_file(package, tmp_path):
    target = tmp_path / "pkg"
    shutil.copytree(package, target)
    (target / schema_file()).write_text("{}", encoding="utf-8")
    result = invoke("map", "validate", target)
    assert result.exit_code == 1 and schema_file() in result.output
    assert "checksum" in result.output
