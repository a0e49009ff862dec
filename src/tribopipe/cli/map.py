"""``tribopipe map``: import, merge, tabulate, show and curate the friction map."""

from __future__ import annotations

import click

from ._common import (
    chosen_map,
    friendly_errors,
    instrument_option,
    lazy_map_option,
    map_option,
    material_filters,
    say,
)
from .fit import fit_cmd
from .mastercurve import master_curve_cmd


@click.group("map")
def map_group() -> None:
    """The friction map: one row per reduced run (Parquet), repeat statistics, tables.

    \b
    Examples:
      tribopipe map import --published            start from the founding paper's map
      tribopipe map import FrictionMap.mat        the published MATLAB table (or its CSV)
      tribopipe map merge other_lab.parquet       fold in another lab's map
      tribopipe map publish -o contribution --lab "Soft Robotics Lab"   a data package
      tribopipe map validate their_package/      check a package someone sent
      tribopipe map merge their_package/          fold it in, each lab's rows kept
      tribopipe map table --format markdown --pin "Dragonskin 30" --temperature 20
      tribopipe map show
      tribopipe map exclude 3fa2c1d09e --reason "pin slipped in the holder"
      tribopipe map fit --pin "Dragonskin 30"     power law μ_K = k·p^(n−1) per pair
      tribopipe map master-curve --pin "Dragonskin 30" --disc steel   over speed and T
    """


map_group.add_command(fit_cmd)
map_group.add_command(master_curve_cmd)


@map_group.command("import")
@click.argument("file", required=False, type=click.Path(dir_okay=False))
@click.option(
    "--published",
    is_flag=True,
    help="Import the founding paper's published map shipped with tribopipe.",
)
@click.option(
    "--source",
    help="Label for where the rows come from (default: published:Berthold2023 for the "
    "published rows, else import:<file name>).",
)
@click.option("--replace", is_flag=True, help="Overwrite rows whose content differs.")
@map_option
@friendly_errors
def import_cmd(
    file: str | None, published: bool, source: str | None, replace: bool, map_path: str
) -> None:
    """Import a FrictionMap table (.mat or CSV, 7 columns: pin, disc, contactForce,
    contactPressure, temperature, measurementNo, cof) into the map.

    Imported rows carry their origin and μ_S as missing. Importing the same rows again
    changes nothing.
    """
    from ..frictionmap import import_table

    if published == (file is not None):
        raise click.UsageError("give a FILE or --published (not both)")
    from ..materials import lab_files, load_vocabulary

    report = import_table(map_path, file, source=source, replace=replace,
                          vocabulary=load_vocabulary(lab_files(".")))
    say(f"map {map_path}: {report.summary()}")


@map_group.command("merge")
@click.argument("other", type=click.Path())
@click.option("--replace", is_flag=True, help="Overwrite our rows where OTHER's content differs.")
@click.option("--lab", help="The lab that measured OTHER's rows that name none (a Parquet "
              "map; a package names its own).")
@map_option
@friendly_errors
def merge_cmd(other: str, replace: bool, lab: str | None, map_path: str) -> None:
    """Fold another friction map (Parquet) or a data package (its folder or
    datapackage.json, as `map publish` writes it) into the map.

    A package is checked first (as `map validate` does) and refused whole when anything is
    wrong; its rows keep their lab. Rows of a Parquet map that name no lab read as this
    map's own: --lab records who measured them (said when it is missing). Runs with the
    same id are stored once; each conflicting run (same id, other values) is listed with
    both values (exit code 1 when any were kept).
    """
    from ..frictionmap import merge_map
    from ..materials import lab_files, load_vocabulary

    merged = merge_map(map_path, other, replace=replace, lab=lab,
                       vocabulary=load_vocabulary(lab_files(".")))
    report = merged.report
    for line in report.conflict_lines(theirs=other):
        say(line)
    for line in merged.notes(other):
        say(line, err=line.startswith("note:"))
    say(f"map {map_path}: {report.summary()}")
    if report.kept_conflicting:
        raise SystemExit(1)


@map_group.command("publish")
@click.argument("folder", required=False, type=click.Path(file_okay=False))
@click.option("-o", "--output", type=click.Path(file_okay=False),
              help="The folder to write the package in (required; a positional FOLDER, the "
              "old spelling, works until the next release).")
@click.option("--lab", required=True,
              help="The laboratory that measured the runs (named in every row and the "
              "citation).")
@click.option("--contact", help="Contact person for the data.")
@click.option("--email", help="Contact email address.")
@click.option("--licence", "licence", default="CC-BY-4.0", show_default=True,
              help="Licence of the data (SPDX id): CC-BY-4.0 (reuse with attribution), "
              "CC0-1.0, CC-BY-SA-4.0, ODC-By-1.0, ODbL-1.0 or PDDL-1.0.")
@click.option("--title", help="Title of the package (default: '<lab> friction map').")
@click.option("--overwrite", is_flag=True, help="Replace a package already in FOLDER.")
@click.option("--allow-synthetic", is_flag=True,
              help="Publish rows flagged synthetic (demo data) too; refused without it.")
@click.option("--traces", "traces_dir", type=click.Path(file_okay=False),
              help="Folder of the runs' reduced traces (default: traces/ beside the map).")
@click.option("--with-raw", is_flag=True,
              help="Include each run's raw export (found in --raw-dir by name and SHA-256).")
@click.option("--raw-dir", "raw_dirs", multiple=True, type=click.Path(file_okay=False),
              help="Folder of the raw exports, searched with its sub-folders (repeatable).")
@click.option("--no-evidence", is_flag=True,
              help="Leave out the traces and raw exports (summary rows only).")
@instrument_option
@map_option
@friendly_errors
def publish_cmd(folder: str | None, output: str | None, lab: str, contact: str | None,
                email: str | None, licence: str, title: str | None, overwrite: bool,
                allow_synthetic: bool, traces_dir: str | None, with_raw: bool,
                raw_dirs: tuple[str, ...], no_evidence: bool, instrument_path: str | None,
                map_path: str) -> None:
    """Write the map as a Frictionless Data Package in the folder -o/--output:
    datapackage.json (schema, units, licence, sources, size and SHA-256 of every file),
    the runs and groups as CSV and Parquet, the 7-column FrictionMap table, the explorer
    page, a README and a CITATION.cff that cites the founding paper.

    The package carries its evidence: each reduced run's trace (Parquet) and, with
    --with-raw, its raw export, each with its SHA-256 and the method and settings that
    reduced it (the defaults, or the instrument file given with --instrument), so that
    `map validate --recompute` can re-derive every μ.

    The data licence defaults to CC-BY-4.0. The package is checked as `map validate`
    would before it is moved into place; it is never half-written. A map with runs
    flagged synthetic (the demo's) is refused unless --allow-synthetic is given.

    \b
    Example:
      tribopipe map publish -o contribution --lab "Soft Robotics Lab, Uni X" \\
          --contact "A. Person" --email a.person@uni-x.example
    """
    from ..config import load_settings
    from ..export.citation import Publisher
    from ..export.publish import publish_map

    if folder is not None and output is not None:
        raise click.UsageError("give the package folder once: -o/--output FOLDER")
    if folder is not None:
        say("note: the positional FOLDER is now -o/--output FOLDER (the old spelling works "
            "until the next release)", err=True)
        output = folder
    if output is None:
        raise click.UsageError("give the folder to write the package in: -o/--output FOLDER")
    done = publish_map(map_path, output,
                       Publisher(lab, contact, email, licence, title),
                       overwrite=overwrite, allow_synthetic=allow_synthetic,
                       evidence=not no_evidence, traces_dir=traces_dir, with_raw=with_raw,
                       raw_dirs=raw_dirs,
                       settings=[load_settings(instrument_path)] if instrument_path else [])
    say(f"wrote {done.path}: {done.n_runs} runs in {len(done.files)} files "
        f"(check it with `tribopipe map validate {done.path}`)")
    if not no_evidence:
        say(f"evidence: {done.n_traces} traces, {done.n_raw} raw exports")
    for note in done.notes:
        say(f"note: {note}")


@map_group.command("validate")
@click.argument("path", required=False, type=click.Path())
@click.option("--recompute", is_flag=True,
              help="Also re-derive μ_S and μ_K of every run from the package's traces and "
              "raw exports, and refuse each row that disagrees beyond its stated U.")
@lazy_map_option
@friendly_errors
def validate_cmd(path: str | None, map_path: str | None, recompute: bool) -> None:
    """Check a data package someone sent (its folder or datapackage.json): schema and
    units of every field, physical ranges, duplicate ids, provenance (lab, hashes,
    versions, times), licences, the size and SHA-256 of every file, and that the Parquet,
    group and FrictionMap tables agree with the runs.

    Prints one line per problem, naming the file, row and field; exit code 1 on any. The
    package is treated as hostile: paths outside it, URLs, huge files and deeply nested
    JSON are refused, never followed.

    PATH may also be a friction map (a .parquet file): its rows are checked as `map
    publish` checks them before writing a package. With --map, or with no PATH, the map
    is checked.

    With --recompute, μ_S and μ_K of every run are re-derived from its raw export where
    the package holds it (read and reduced again with the package's settings), else
    from its reduced trace; a row whose stored value differs by more than its stated
    U = 2u is refused, naming the row and both values. The account says which rows were
    checked from the trace only and which carry no evidence.
    """
    from ..frictionmap import check_package

    if path is not None and map_path is not None:
        raise click.UsageError("give PATH or --map, not both")
    if path is None:
        path = chosen_map(map_path)
    if recompute and path.lower().endswith(".parquet"):
        raise click.UsageError("--recompute checks a package against its evidence; a map "
                               "file holds none (publish it first: `tribopipe map publish`)")
    if recompute:
        from ..evidence import recompute_package

        again = recompute_package(path)
        for note in again.check.notes:
            say(f"note: {note}")
        for line in again.lines():
            say(line)
        for line in again.account():
            say(line)
        if not again.ok:
            raise SystemExit(1)
        say(again.check.verdict() + "; every re-derived μ agrees within its U")
        return
    if path.lower().endswith(".parquet"):
        from ..frictionmap.profile import map_upgrade_note
        from ..frictionmap.summary import check_map_file
        from ..materials import lab_files, load_vocabulary

        problems, verdict, info = check_map_file(path, load_vocabulary(lab_files(".")))
        upgraded = map_upgrade_note(int(info["schema_version"]))
        if upgraded is not None:
            say(f"note: {upgraded}")
        for line in problems:
            say(line)
        say(verdict)
        if problems:
            raise SystemExit(1)
        return
    result = check_package(path, keep_runs=False)  # the verdict, not the runs
    for note in result.notes:
        say(f"note: {note}")
    for line in result.lines():
        say(line)
    if not result.ok:
        raise SystemExit(1)
    say(result.verdict())


@map_group.command("table")
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["csv", "markdown", "latex", "xlsx", "frictionmap"]),
    default="csv",
    show_default=True,
    help="Output format. 'latex' compiles as written with booktabs and siunitx; 'xlsx' is "
    "a spreadsheet with one sheet per layout and a notes sheet (needs -o); 'frictionmap' "
    "is the published 7-column CSV, one row per run.",
)
@click.option(
    "--layout",
    type=click.Choice(["group", "abstract", "paper"]),
    default="group",
    show_default=True,
    help="'group': conditions + repeat statistics; 'abstract': pin, disc, pressure, "
    "temperature, mean μ_K (the paper's Table 2); 'paper': a compact table to publish, "
    "n, μ_S ± U and μ_K ± U (expanded uncertainty, k = 2, rounded to two significant "
    "digits) and flags.",
)
@click.option("--pin", multiple=True, help="Only this pin material (repeatable).")
@click.option("--disc", multiple=True, help="Only this disc material (repeatable).")
@click.option(
    "--temperature", "temperature_C", type=float, multiple=True, help="Only this nominal °C."
)
@click.option("--by-speed", is_flag=True, help="Also split condition groups by sliding speed.")
@click.option("--decimal", type=click.Choice([".", ","]), default=".", show_default=True,
              help="Decimal mark of a CSV: ',' writes it for a decimal-comma locale (cells "
              "separated by ';'), as Excel there opens a CSV.")
@click.option("--method", multiple=True,
              help="Only runs of this test method (repeatable): 'rheometer pin-on-disc', "
              "'sled D1894', 'linear reciprocating' or 'rotary pin-on-disc'.")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Write to FILE. Default: standard output (not for xlsx).")
@map_option
@friendly_errors
def table_cmd(
    fmt: str,
    layout: str,
    pin: tuple[str, ...],
    disc: tuple[str, ...],
    temperature_C: tuple[float, ...],
    by_speed: bool,
    decimal: str,
    method: tuple[str, ...],
    output: str | None,
    map_path: str,
) -> None:
    """Regenerate a table from the friction map (to stdout, or -o FILE).

    \b
      tribopipe map table --layout paper --format latex -o table.tex
      tribopipe map table --format xlsx -o friction_map.xlsx
      tribopipe map table --layout paper --decimal , -o table.csv
    """
    from ..frictionmap.snapshot import open_map
    from ..stats import GROUP_INPUT_COLUMNS

    # the group layouts read the groups (stored in a map folder) and the columns of the
    # statistics where none are stored; the 7-column table reads the runs themselves
    snap = open_map(map_path, None if fmt == "frictionmap" else GROUP_INPUT_COLUMNS)
    pin, disc = material_filters(snap, pin, disc)  # against the names the map holds
    if fmt == "xlsx":
        from ..export.workbook import export_workbook

        if output is None:
            raise click.UsageError("--format xlsx writes a binary file: give -o FILE.xlsx")
        source = click.get_current_context().get_parameter_source("layout")
        if source is not None and source.name == "COMMANDLINE":
            say("note: an xlsx holds every layout, one sheet each: --layout is not needed",
                err=True)
        if decimal != ".":
            raise click.UsageError("--decimal is for --format csv (an xlsx stores numbers)")
        written = export_workbook(map_path, output, pin=pin, disc=disc,
                                  temperature_C=temperature_C, by_speed=by_speed,
                                  method=method)
        say(f"wrote {written}", err=True)
        return
    from ..export.tables import export_table

    text = export_table(
        snap,
        output,
        fmt=fmt,
        layout=layout,
        pin=pin,
        disc=disc,
        temperature_C=temperature_C,
        by_speed=by_speed,
        decimal=decimal,
        method=method,
    )
    if output is None:
        click.echo(text, nl=False)
    else:
        say(f"wrote {output}", err=True)


@map_group.command("compare")
@click.option("--quantity", type=click.Choice(["mu_k", "mu_s"]), default="mu_k",
              show_default=True, help="The coefficient to compare.")
@click.option("--format", "fmt", type=click.Choice(["text", "csv", "markdown"]),
              default="text", show_default=True, help="How to print the comparison.")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Write to FILE instead of standard output.")
@map_option
@friendly_errors
def compare_cmd(quantity: str, fmt: str, output: str | None, map_path: str) -> None:
    """Labs side by side at every condition two of them measured.

    Per condition and pair of labs: each lab's n and mean ± U (k = 2, its own
    uncertainty), the difference and its U, ISO 13528's En number (|En| > 1: the labs
    disagree beyond their stated uncertainties) and each lab's z score against the
    condition's pooled mean with σ_pt = the map's reproducibility s_R (ISO 5725-2), and
    whether the labs disagree beyond R. Then the map's s_r, s_R, r and R.
    """
    from ..export.tables import to_csv, to_markdown
    from ..files import write_text_atomic
    from ..frictionmap import read_map
    from ..rounding import plus_minus, round_gum
    from ..stats import group_statistics, lab_comparison, reproducibility

    runs = read_map(map_path)
    table = lab_comparison(runs, quantity)
    rep = reproducibility(group_statistics(runs), quantity)
    footer = (f"{quantity}: s_r = {rep.s_r:.3g}, s_R = {rep.s_R:.3g}, r = {rep.r:.3g}, "
              f"R = {rep.R:.3g} over {rep.n_conditions} condition(s) several labs measured "
              "(ISO 5725-2)")
    if fmt == "csv":
        text = to_csv(table)
    elif fmt == "markdown":
        text = to_markdown(table) + "\n" + footer + "\n"
    else:
        lines = []
        if table.empty:
            lines.append("no condition was measured by two labs")
        several_methods = table["test_method"].nunique() > 1
        for r in table.to_dict(orient="records"):
            lines.append(f"{r['pin']} on {r['disc']}, {r['pressure_kPa']:.4g} kPa, "
                         f"{r['temperature_C']:g} °C, {r['nominal_speed_mm_s']:.2g} mm/s"
                         + (f", {r['test_method']}" if several_methods else ""))
            for side in ("a", "b"):
                lines.append(f"  {r['lab_' + side]}: n = {r['n_' + side]}, "
                             f"{plus_minus(r['mean_' + side], r['U_' + side])}, "
                             f"z = {r['z_' + side]:.2f}")
            diff, u_diff = round_gum(r["difference"], r["U_difference"])
            lines.append(f"  difference {diff} ± {u_diff}, "
                         f"En = {r['En']:.2f}"
                         + ("; labs disagree beyond R" if r["labs_disagree"] else ""))
        lines.append(footer)
        text = "\n".join(lines) + "\n"
    if output:
        write_text_atomic(output, text, newline="")
        say(f"wrote {output}", err=True)
    else:
        for line in text.splitlines():
            say(line)


@map_group.command("show")
@click.option("--runs", "runs_listed", is_flag=True,
              help="Then list every run: id, file [test / result / interval], pin / disc, "
                   "nominal force and temperature, repeat, mu_k, mu_s, flags.")
@click.option("--groups", "groups_listed", is_flag=True,
              help="Then the condition groups as the compact 'paper' table: n, μ_S ± U, "
                   "μ_K ± U (k = 2) and flags.")
@map_option
@friendly_errors
def show_cmd(runs_listed: bool, groups_listed: bool, map_path: str) -> None:
    """Summarise the map: runs, contact pairs, conditions, sources, labs, flags, excluded
    runs (with the file and test each came from) and the pooled repeatability."""
    from ..export.tables import map_paper_text
    from ..frictionmap import map_summary
    from ..frictionmap.snapshot import open_map
    from ..frictionmap.summary import SUMMARY_COLUMNS

    # the one read and check of the map: the columns the summary uses of every run
    # (every column with --runs); its excluded and reviewed runs are read whole apart,
    # from the same commit; a map folder's groups are stored, not grouped again
    snap = open_map(map_path, None if runs_listed else SUMMARY_COLUMNS)
    click.echo(map_summary(snap, runs_listed=runs_listed))
    if groups_listed:
        click.echo(map_paper_text(snap), nl=False)


@map_group.command("exclude")
@click.argument("ids", nargs=-1, required=True)
@click.option("--reason", required=True, help="Why the runs are left out (recorded).")
@map_option
@friendly_errors
def exclude_cmd(ids: tuple[str, ...], reason: str, map_path: str) -> None:
    """Leave runs (by measurement id or a unique prefix of 6+ digits) out of the statistics.
    They stay in the map with the reason."""
    from ..frictionmap import exclude_runs

    changed = exclude_runs(map_path, ids, reason)
    say(f"excluded {len(changed)} run(s)" + (": " + ", ".join(changed) if changed else ""))


@map_group.command("include")
@click.argument("ids", nargs=-1, required=True)
@map_option
@friendly_errors
def include_cmd(ids: tuple[str, ...], map_path: str) -> None:
    """Take excluded runs back into the statistics."""
    from ..frictionmap import include_runs

    changed = include_runs(map_path, ids)
    say(f"included {len(changed)} run(s)" + (": " + ", ".join(changed) if changed else ""))


@map_group.command("upgrade")
@map_option
@friendly_errors
def upgrade_cmd(map_path: str) -> None:
    """Convert a map kept as one Parquet file (the format before map folders) into a map
    folder of parts at the same path, so that every later write adds a part instead of
    rewriting the whole map. Every row is checked on the way; the old file is kept as
    <map>.bak. A map folder already is left as it is."""
    from ..frictionmap.store import upgrade_map

    n_runs, kept = upgrade_map(map_path)
    if kept is None:
        say(f"{map_path}: a map folder of parts already ({n_runs} runs); nothing to do")
    else:
        say(f"{map_path}: converted to a map folder of parts ({n_runs} runs); the single "
            f"file is kept as {kept}")


@map_group.command("compact")
@map_option
@friendly_errors
def compact_cmd(map_path: str) -> None:
    """Rewrite a map folder's parts as one part (with the safety of every write: the new
    part fsynced, the manifest swapped atomically, the previous commit kept as
    _manifest.json.bak). Writes keep the number of parts small on their own; compact
    before copying a map, or after many exclusions."""
    from ..frictionmap.store import compact_map

    before, after = compact_map(map_path)
    say(f"{map_path}: {before} part(s) → {after}")
