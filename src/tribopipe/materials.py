"""The one vocabulary of materials: canonical names, aliases, class and identifying
properties, and the resolution of every incoming pin or disc name.

The package ships ``tribopipe/data/materials.toml`` (every material of the founding map
and a few more); a lab extends it with a file of the same form (:func:`load_vocabulary`).
Every name that comes in (a pattern, a manifest cell, an option, a merged map or
package, an imported table) goes through this module at the edge, and only here is it
decided what a name means: :meth:`Vocabulary.resolve` (one name) and
:meth:`Vocabulary.resolve_all` (every name of a file, a package or a command at once)
give the canonical name (stored in the map; the name as given is kept in
``pin_as_given``/``disc_as_given``), or ONE :class:`MaterialError` of one line naming
every name that does not resolve, each with a did-you-mean, and the fix
(:func:`add_fix`: the ``tribopipe materials add`` command or the line for the lab's
file). An option that filters what the map holds (``query --pin``) is resolved by
:meth:`Vocabulary.filter_name` against the map's own names. Names are compared by
:func:`name_key`: case, accents, spaces and punctuation ignored, so "Dragon Skin 30",
"dragonskin-30" and "Dragonskin 30" are one name. An alias listed under two materials is
ambiguous and refused with both (the lab says which it means).

A material file: a ``[materials]`` table, one entry per canonical name, each a table with
``class`` (one of :data:`CLASSES`) and optional ``aliases`` (list), ``supplier``,
``shore``, ``finish``, ``note``. One line adds a material::

    [materials]
    "Sylgard 184" = { class = "silicone elastomer", supplier = "Dow" }
"""

from __future__ import annotations

import difflib
import functools
import os
import shlex
import tomllib
import unicodedata
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import ConfigError, ReadError, TribopipeError, ValidationError
from .files import read_regular, write_text_atomic
from .validate import check_name, name_problem

#: the classes a material may have
CLASSES: tuple[str, ...] = ("silicone elastomer", "elastomer", "metal", "polymer", "glass",
                            "ceramic", "wood", "paper", "composite", "other")
#: the optional text properties of a material, besides its class and aliases
PROPERTIES: tuple[str, ...] = ("supplier", "shore", "finish", "note")
#: the name of a lab's own materials file, found beside its campaign config
LAB_FILE = "materials.toml"
#: the largest materials file read [bytes]
MAX_FILE_BYTES = 4 * 1024 * 1024
#: how close a name must be to suggest it (difflib ratio)
SUGGEST_CUTOFF = 0.6


class MaterialError(TribopipeError):
    """A material name that the vocabulary does not know, or knows twice (ambiguous)."""


@dataclass(frozen=True)
class Material:
    """One material: its canonical ``name``, ``material_class`` (one of :data:`CLASSES`),
    ``aliases`` (spellings, vendor codes, translations), the identifying properties
    ``supplier``, ``shore`` (Shore hardness as the supplier states it), ``finish`` (a
    disc's surface) and ``note`` (empty when unknown), and the file it came from."""

    name: str
    material_class: str
    aliases: tuple[str, ...] = ()
    supplier: str = ""
    shore: str = ""
    finish: str = ""
    note: str = ""
    origin: str = "tribopipe"

    def describe(self) -> str:
        """``name (class; supplier, Shore 30A, finish ...)`` on one line."""
        props = [self.material_class] + [
            f"{'Shore ' if p == 'shore' else ''}{getattr(self, p)}"
            for p in PROPERTIES if getattr(self, p)]
        return f"{self.name} ({'; '.join(props[:1])}{', ' if len(props) > 1 else ''}"\
               f"{', '.join(props[1:])})"


def name_key(name: str) -> str:
    """The form two names are compared in: symbols (™, ®) dropped, NFKD, accents and
    every character that is not a letter or digit dropped, case folded ("Dragon Skin™ 30"
    → "dragonskin30")."""
    plain = "".join(c for c in name if not unicodedata.category(c).startswith("S"))
    decomposed = unicodedata.normalize("NFKD", plain)
    return "".join(c for c in decomposed if c.isalnum()).casefold()


def name_words(text: str) -> tuple[str, ...]:
    """The words of a text as names are matched in it: symbols dropped, NFKD, accents
    dropped, case folded, split at every character that is not a letter or digit."""
    plain = "".join(c for c in text if not unicodedata.category(c).startswith("S"))
    decomposed = unicodedata.normalize("NFKD", plain)
    kept = "".join(c if c.isalnum() else " " for c in decomposed
                   if not unicodedata.combining(c))
    return tuple(kept.casefold().split())


@dataclass(frozen=True)
class Resolved:
    """A name resolved: the canonical ``name`` and the name ``given``."""

    name: str
    given: str

    @property
    def changed(self) -> bool:
        """True when the given name is not written as the canonical one."""
        return self.name != self.given


@dataclass(frozen=True)
class Vocabulary:
    """The materials known, by canonical name (:func:`load_vocabulary`)."""

    materials: tuple[Material, ...]

    @functools.cached_property
    def _index(self) -> dict[str, tuple[str, ...]]:
        index: dict[str, list[str]] = {}
        for m in self.materials:
            for text in (m.name, *m.aliases):
                key = name_key(text)
                if key and m.name not in index.setdefault(key, []):
                    index[key].append(m.name)
        # a canonical name is never ambiguous: it names its own material
        for m in self.materials:
            index[name_key(m.name)] = [m.name]
        return {k: tuple(v) for k, v in index.items()}

    @functools.cached_property
    def _by_name(self) -> dict[str, Material]:
        return {m.name: m for m in self.materials}

    def get(self, name: str) -> Material | None:
        """The material of a canonical ``name``, else ``None``."""
        return self._by_name.get(name)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._by_name

    def candidates(self, name: str) -> tuple[str, ...]:
        """The canonical names ``name`` may stand for: one (known), several (ambiguous)
        or none (unknown)."""
        return self._index.get(name_key(name), ())

    def suggest(self, name: str) -> tuple[str, ...]:
        """Up to three canonical names close to an unknown ``name`` (did-you-mean)."""
        key = name_key(name)
        keys = difflib.get_close_matches(key, list(self._index), n=6, cutoff=SUGGEST_CUTOFF)
        out: list[str] = []
        for k in keys:
            for canonical in self._index[k]:
                if canonical not in out:
                    out.append(canonical)
        return tuple(out[:3])

    def problem(self, name: str, what: str = "material") -> str | None:
        """Why ``name`` does not resolve (one line, with a did-you-mean or the choices),
        or ``None`` when it does."""
        found = self.candidates(name)
        if len(found) == 1:
            return None
        if found:
            choices = " or ".join(repr(c) for c in found)
            return f"{what} {name!r} is ambiguous: {choices}"
        near = self.suggest(name)
        hint = f"; did you mean {' or '.join(repr(n) for n in near)}?" if near else ""
        return f"unknown {what} {name!r}{hint}"

    def resolve(self, name: str, what: str = "material") -> Resolved:
        """``name`` (checked as a name) resolved to its canonical name; a
        :class:`MaterialError` of one line (did-you-mean, or the choices of an ambiguous
        name, and how to add a material) otherwise."""
        check_name(name, what)
        problem = self.problem(name, what)
        if problem is not None:
            raise MaterialError(problem, hint=ADD_HINT)
        return Resolved(self.candidates(name)[0], name)

    def resolve_all(self, named: Iterable[tuple[str, str]],
                    where: str | os.PathLike[str] | None = None) -> dict[tuple[str, str], str]:
        """Every ``(what, name)`` of ``named`` (``what``: "pin" or "disc") → its canonical
        name; when any does not resolve, ONE :class:`MaterialError` naming every such
        name (each with its did-you-mean or choices, in the order first met) and the fix
        (:func:`add_fix`), about ``where`` (a file, a package)."""
        out: dict[tuple[str, str], str] = {}
        seen: set[tuple[str, str]] = set()
        problems: list[str] = []
        unknown: list[str] = []
        for what, name in named:
            if (what, name) in seen:
                continue
            seen.add((what, name))
            bad = name_problem(name)
            problem = f"{what}: {bad}" if bad is not None else self.problem(name, what)
            if problem is None:
                out[(what, name)] = self.candidates(name)[0]
                continue
            problems.append(problem)
            if bad is None and not self.candidates(name) and name not in unknown:
                unknown.append(name)
        if problems:
            head = (problems[0] if len(problems) == 1 else
                    f"{len(problems)} material names not in the vocabulary: "
                    + joined_problems(problems))
            raise MaterialError(head, path=where, hint=add_fix(unknown))
        return out

    def filter_name(self, name: str, what: str, held: Iterable[str]) -> str:
        """The name a filter option (``--pin``, ``--disc`` of a command that reads the
        map) means, given the names the map ``held``: a held name written the same way
        (:func:`name_key`) as ``name``; else the canonical name ``name`` resolves to, or
        the one held name that resolves to it (a row stored before names were
        resolved); else a :class:`MaterialError` of one line with a did-you-mean over the
        vocabulary and the held names (an ambiguous name: its choices)."""
        check_name(name, what)
        held = sorted({str(h) for h in held})
        key = name_key(name)
        same = [h for h in held if name_key(h) == key]
        if same:
            return same[0]
        found = self.candidates(name)
        if len(found) == 1:
            canonical = found[0]
            if canonical in held:
                return canonical
            alike = [h for h in held if self.candidates(h) == (canonical,)]
            return alike[0] if len(alike) == 1 else canonical
        if found:
            raise MaterialError(f"{what} {name!r} is ambiguous: "
                                + " or ".join(repr(c) for c in found),
                                hint="give the material's full name")
        keys = {name_key(h): h for h in held}
        near = list(self.suggest(name))
        near += [keys[k] for k in difflib.get_close_matches(key, list(keys), n=3,
                                                            cutoff=SUGGEST_CUTOFF)
                 if keys[k] not in near]
        hint = f"; did you mean {' or '.join(repr(n) for n in near[:3])}?" if near else ""
        shown = ", ".join(held[:12]) + (" ..." if len(held) > 12 else "")
        raise MaterialError(f"unknown {what} {name!r}{hint}",
                            hint=f"the map holds: {shown}" if held else "the map is empty")

    @functools.cached_property
    def _phrases(self) -> dict[tuple[str, ...], tuple[str, ...]]:
        """Every name and alias as its word sequence (:func:`name_words`) → the canonical
        names it stands for."""
        out: dict[tuple[str, ...], list[str]] = {}
        for m in self.materials:
            for text in (m.name, *m.aliases):
                words = name_words(text)
                if words and m.name not in out.setdefault(words, []):
                    out[words].append(m.name)
        return {k: tuple(v) for k, v in out.items()}

    def mentioned(self, text: str) -> list[tuple[str, ...]]:
        """The materials a free text names (a Test name, a sample field), in order: each
        mention as the canonical names it may stand for (one, or several for an ambiguous
        alias). Words are matched whole, the longest name first ("acrylic glass" is not
        also "glass")."""
        words = name_words(text)
        longest = max((len(k) for k in self._phrases), default=0)
        found: list[tuple[str, ...]] = []
        i = 0
        while i < len(words):
            for size in range(min(longest, len(words) - i), 0, -1):
                hit = self._phrases.get(tuple(words[i:i + size]))
                if hit is not None:
                    if hit not in found:
                        found.append(hit)
                    i += size
                    break
            else:
                i += 1
        return found

    def with_materials(self, extra: Iterable[Material]) -> Vocabulary:
        """This vocabulary and ``extra``: a material of the same canonical name replaces
        the shipped one (a lab may add aliases or properties)."""
        added = list(extra)
        names = {m.name for m in added}
        return Vocabulary(tuple(m for m in self.materials if m.name not in names) + tuple(added))


#: how to add a material, for every refusal
ADD_HINT = (f"fix the name, map it in the campaign's [names], or add the material: one line "
            f"in {LAB_FILE} beside the campaign config, or `tribopipe materials add NAME "
            f"--class CLASS`")


#: how many names a refusal of several names lists (a package of 10³ lots' own names
#: would otherwise be refused in one line of some 100 kB); the rest are counted
NAMES_SHOWN = 10


def joined_problems(problems: Sequence[str]) -> str:
    """The problems of a refusal of several names in one line: the first
    :data:`NAMES_SHOWN`, then how many more."""
    more = len(problems) - NAMES_SHOWN
    return "; ".join(problems[:NAMES_SHOWN]) + (f"; and {more} more" if more > 0 else "")


def add_fix(names: Sequence[str]) -> str:
    """The one-line fix for names the vocabulary lacks: correct a misspelt one, or add a
    genuinely new material with one command (or one line in the lab's
    :data:`LAB_FILE`); the general :data:`ADD_HINT` when ``names`` is empty (ambiguous
    names only: say which material is meant)."""
    if not names:
        return ADD_HINT
    first = names[0]
    rest = ", ".join(repr(n) for n in names[1:NAMES_SHOWN]) + (
        f" and {len(names) - NAMES_SHOWN} more" if len(names) > NAMES_SHOWN else "")
    more = f" (and the same for {rest})" if names[1:] else ""
    line = material_line(Material(name=first, material_class="CLASS"))
    return (f"fix a misspelt name; a new material is one command, `tribopipe materials add "
            f"{shlex.quote(first)} --class CLASS`, or one line under [materials] in "
            f"{LAB_FILE}: {line}{more}; CLASS is one of {', '.join(CLASSES)}")


def _text(value: Any, where: str, key: str) -> str:
    if not isinstance(value, str):
        raise ConfigError(f"{where}: {key} must be text, got {value!r}")
    problem = name_problem(value) if value else None
    if problem is not None:
        raise ConfigError(f"{where}: {key}: {problem}")
    return value


def parse_materials(data: Mapping[str, Any], origin: str) -> tuple[Material, ...]:
    """The materials of a parsed materials file (its ``[materials]`` table, see the module
    docstring); a :class:`ConfigError` naming the file and the material otherwise."""
    unknown = sorted(set(data) - {"materials"})
    if unknown:
        raise ConfigError(f"unknown table(s) {', '.join(unknown)}; expected [materials]",
                          path=origin)
    table = data.get("materials", {})
    if not isinstance(table, dict):
        raise ConfigError("[materials] must be a table of materials", path=origin)
    out: list[Material] = []
    for name, entry in table.items():
        where = f"[materials] {name[:40]!r}"
        try:
            check_name(name, where)
        except ValidationError as exc:
            raise ConfigError(exc.problem, path=origin) from None
        if not isinstance(entry, dict):
            raise ConfigError(f"{where} must be a table, e.g. {{ class = \"metal\" }}",
                              path=origin)
        extra = sorted(set(entry) - {"class", "aliases", *PROPERTIES})
        if extra:
            raise ConfigError(f"{where}: unknown key(s) {', '.join(extra)}; expected class, "
                              f"aliases, {', '.join(PROPERTIES)}", path=origin)
        cls = entry.get("class")
        if cls not in CLASSES:
            raise ConfigError(f"{where}: class must be one of {', '.join(CLASSES)}, "
                              f"got {cls!r}", path=origin)
        aliases = entry.get("aliases", [])
        if not isinstance(aliases, list):
            raise ConfigError(f"{where}: aliases must be a list of names", path=origin)
        try:
            out.append(Material(
                name=name, material_class=cls,
                aliases=tuple(check_name(_text(a, where, "alias"), f"{where} alias")
                              for a in aliases),
                origin=origin,
                **{p: _text(entry.get(p, ""), where, p) for p in PROPERTIES}))
        except (ConfigError, ValidationError) as exc:
            raise ConfigError(exc.problem, path=origin) from None
    return tuple(out)


def read_materials(path: str | Path) -> tuple[Material, ...]:
    """The materials of a lab's file (TOML, the module docstring's form)."""
    p = Path(path)
    try:
        raw = read_regular(p, max_bytes=MAX_FILE_BYTES, what="a materials file (TOML)")
    except ReadError as exc:
        raise ConfigError(f"cannot read materials file: {exc.problem}", path=p) from None
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", path=p) from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"not UTF-8 text (byte {exc.start})", path=p) from None
    return parse_materials(data, str(p))


@functools.lru_cache(maxsize=1)
def shipped_vocabulary() -> Vocabulary:
    """The vocabulary shipped in the package (``tribopipe/data/materials.toml``)."""
    from importlib import resources

    text = resources.files("tribopipe").joinpath("data", "materials.toml").read_text("utf-8")
    return Vocabulary(parse_materials(tomllib.loads(text), "tribopipe"))


def load_vocabulary(files: Sequence[str | Path] = ()) -> Vocabulary:
    """The shipped vocabulary extended by a lab's ``files`` (later files win)."""
    vocabulary = shipped_vocabulary()
    for f in files:
        vocabulary = vocabulary.with_materials(read_materials(f))
    return vocabulary


def lab_files(folder: str | Path | None, named: Sequence[str | Path] = ()) -> list[Path]:
    """A lab's materials files: :data:`LAB_FILE` in ``folder`` (a campaign config's
    folder) when it is there, then the files ``named``."""
    out: list[Path] = []
    if folder is not None:
        candidate = Path(folder) / LAB_FILE
        if candidate.is_file():
            out.append(candidate)
    out.extend(Path(n) for n in named if Path(n) not in out)
    return out


def material_line(material: Material) -> str:
    """The one TOML line under ``[materials]`` that adds ``material``."""
    import json

    fields = [f"class = {json.dumps(material.material_class, ensure_ascii=False)}"]
    if material.aliases:
        fields.append("aliases = [" + ", ".join(json.dumps(a, ensure_ascii=False)
                                                for a in material.aliases) + "]")
    fields += [f"{p} = {json.dumps(getattr(material, p), ensure_ascii=False)}"
               for p in PROPERTIES if getattr(material, p)]
    return f"{json.dumps(material.name, ensure_ascii=False)} = {{ {', '.join(fields)} }}"


def add_material(path: str | Path, material: Material) -> str:
    """Add ``material`` to a lab's materials file (created when missing) as one line under
    ``[materials]``, and return that line. Refused (:class:`ConfigError`) when the file
    or the shipped vocabulary already knows the name or one of its aliases as another
    material, or the file is not a materials file; the file is written atomically."""
    p = Path(path)
    existing: tuple[Material, ...] = read_materials(p) if p.exists() else ()
    vocabulary = load_vocabulary().with_materials(existing)
    for text in (material.name, *material.aliases):
        taken = [c for c in vocabulary.candidates(text) if c != material.name]
        if taken:
            raise ConfigError(f"{text!r} already names {taken[0]!r}", path=p,
                              hint="choose another name, or add an alias to that material")
    if material.name in vocabulary:
        raise ConfigError(f"{material.name!r} is already a material", path=p)
    line = material_line(material)
    text = p.read_text("utf-8") if p.exists() else ""
    if "[materials]" not in text:
        text = (text.rstrip("\n") + "\n\n" if text.strip() else "") + "[materials]\n"
    if not text.endswith("\n"):
        text += "\n"
    new_text = _insert_after_table(text, line)
    parse_materials(tomllib.loads(new_text), str(p))  # the file still reads
    write_text_atomic(p, new_text)
    return line


def _insert_after_table(text: str, line: str) -> str:
    """``text`` with ``line`` placed as the last line of its ``[materials]`` table."""
    lines = text.splitlines()
    start = next(i for i, x in enumerate(lines) if x.strip() == "[materials]")
    end = start + 1
    while end < len(lines) and not lines[end].lstrip().startswith("["):
        end += 1
    while end > start + 1 and not lines[end - 1].strip():
        end -= 1
    return "\n".join(lines[:end] + [line] + lines[end:]) + "\n"
