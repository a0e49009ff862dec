"""Strict readers for the simulator input tribopipe writes, as each engine would parse it.

Each reader accepts only what the target language allows in our files and fails on
anything else: a line that is neither comment, keyword nor data, a Python statement
other than the few we write, an XML element we do not write. The tests read every
written file back with these.
"""

from __future__ import annotations

import ast
import xml.etree.ElementTree as ET
from collections.abc import Callable


def parse_abaqus(text: str) -> dict[str, dict]:
    """{interaction name: {"options": [(keyword, params)], "rows": [[floats], ...]}}.

    Lines are comments (``**``), keyword lines (``*KEY, P=V``) or data lines of numbers;
    only ``*SURFACE INTERACTION`` and ``*FRICTION`` keywords may appear.
    """
    blocks: dict[str, dict] = {}
    current = None
    for raw in text.split("\n"):
        line = raw.strip()
        if not line or line.startswith("**"):
            continue
        assert len(raw) <= 256, f"ABAQUS line longer than 256 characters: {raw[:40]}..."
        if line.startswith("*"):
            keyword, *params = [p.strip() for p in line.split(",")]
            keyword = keyword.upper()
            assert keyword in ("*SURFACE INTERACTION", "*FRICTION"), f"keyword {line!r}"
            if keyword == "*SURFACE INTERACTION":
                name = dict(p.split("=") for p in params)["NAME"]
                assert name not in blocks, f"interaction {name} defined twice"
                current = blocks.setdefault(name, {"options": [], "rows": []})
            else:
                assert current is not None, f"{line} outside a *SURFACE INTERACTION"
                current["options"].append((keyword, [p.upper() for p in params]))
            continue
        assert current is not None, f"data line {line!r} before any keyword"
        current["rows"].append([float(v) for v in line.split(",")])
    return blocks


def parse_ansys(text: str) -> dict[int, list[tuple[float | None, float, float]]]:
    """{material: [(temperature, pressure, mu), ...]} from TB/TBFIELD/TBDATA commands;
    every other non-comment line (and any ``$`` command separator) is an error."""
    tables: dict[int, list] = {}
    mat = temp = pres = None
    for raw in text.split("\n"):
        assert "$" not in raw, f"command separator in {raw!r}"
        line = raw.split("!")[0].strip()
        if not line:
            continue
        cmd, *args = line.split(",")
        if cmd == "TB":
            assert args[0] == "FRIC" and args[4] == "ISO"
            mat = int(args[1])
            tables[mat] = []
            temp = pres = None
        elif cmd == "TBFIELD":
            if args[0] == "TEMP":
                temp = float(args[1])
            else:
                assert args[0] == "NPRES"
                pres = float(args[1])
        elif cmd == "TBDATA":
            assert args[0] == "1"
            tables[mat].append((temp, pres, float(args[1])))
        else:
            raise AssertionError(f"unexpected command {cmd!r}")
    return tables


def parse_lsdyna(text: str) -> list[tuple[str, list[str]]]:
    """[(keyword, [card lines])] as LS-DYNA reads a keyword file: ``$`` lines are comments,
    a line starting with ``*`` opens a keyword, every other line (blank too) is a card."""
    keywords: list[tuple[str, list[str]]] = []
    for raw in text.split("\n")[:-1]:  # the file ends with a newline
        if raw.startswith("$"):
            continue
        if raw.startswith("*"):
            keywords.append((raw.strip(), []))
            continue
        assert keywords, f"card {raw!r} before any keyword"
        assert len(raw) <= 80, f"card longer than 80 columns: {raw!r}"
        keywords[-1][1].append(raw)
    return keywords


def fields10(card: str, n: int = 8) -> list[str]:
    """The ``n`` 10-character fields of a standard-format card, stripped ('' = blank)."""
    return [card[i * 10:(i + 1) * 10].strip() for i in range(n)]


def lsdyna_contact(text: str) -> dict:
    """The friction-relevant fields of the one *CONTACT_..._ID keyword in ``text``."""
    keywords = parse_lsdyna(text)
    names = [k for k, _ in keywords]
    assert names == ["*KEYWORD", "*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID", "*END"], names
    cards = keywords[1][1]
    assert len(cards) == 4, cards  # ID card + mandatory cards 1-3
    cid, heading = cards[0][:10].strip(), cards[0][10:80].strip()
    surfa, surfb, surfatyp, surfbtyp, *_ = fields10(cards[1])
    fs, fd, dc, *rest = fields10(cards[2])
    assert not any(rest), f"card 2 fields beyond DC must be blank (defaults): {cards[2]!r}"
    assert not cards[3].strip(), "card 3 is written blank (defaults)"
    return {"cid": int(cid), "heading": heading, "surfa": int(surfa), "surfb": int(surfb),
            "surfatyp": int(surfatyp), "surfbtyp": int(surfbtyp),
            "fs": float(fs), "fd": float(fd), "dc": float(dc)}


def xml_root(text: str, tag: str) -> ET.Element:
    """The whole file parsed as XML (comments and all): one root element ``tag``."""
    root = ET.fromstring(text)
    assert root.tag == tag
    return root


def mujoco_pair(text: str) -> ET.Element:
    """The one ``<pair>`` of a MuJoCo file that holds nothing but ``<contact><pair/>``."""
    root = xml_root(text, "mujoco")
    assert [e.tag for e in root.iter()] == ["mujoco", "contact", "pair"]
    return root.find("contact/pair")


def sofa_response(text: str) -> ET.Element:
    """The one ``CollisionResponse`` of a SOFA fragment (``<Node>`` holding only it)."""
    root = xml_root(text, "Node")
    assert [e.tag for e in root.iter()] == ["Node", "CollisionResponse"]
    return root.find("CollisionResponse")


def pyelastica_values(text: str) -> dict[str, object]:
    """{PAIR, static_mu_array, kinetic_mu_array} from a PyElastica file that holds nothing
    but ``import numpy as np``, the ``PAIR`` literal and the two ``np.array([...])``."""
    found: dict[str, object] = {}
    body = ast.parse(text).body
    first, *assigns = body
    assert isinstance(first, ast.Import)
    assert [(a.name, a.asname) for a in first.names] == [("numpy", "np")]
    for node in assigns:
        assert isinstance(node, ast.Assign) and len(node.targets) == 1
        name = node.targets[0].id
        if name == "PAIR":
            assert isinstance(node.value, ast.Tuple)
            found[name] = ast.literal_eval(node.value)
        else:
            call = node.value
            assert isinstance(call, ast.Call) and not call.keywords
            assert isinstance(call.func, ast.Attribute) and call.func.attr == "array"
            assert isinstance(call.func.value, ast.Name) and call.func.value.id == "np"
            found[name] = ast.literal_eval(call.args[0])
    assert sorted(found) == ["PAIR", "kinetic_mu_array", "static_mu_array"]
    return found


def usd_values(text: str) -> dict[str, object]:
    """{"static", "dynamic", "mode"} of a ``.usda`` layer we write, read without pxr.

    Lines are ``#`` comments, blank, or one of the layer's fixed structural lines; the
    friction and combine-mode lines give the values. Anything else is an error.
    """
    lines = text.split("\n")
    assert lines[0] == "#usda 1.0", lines[0]
    fixed = {
        "(", "    metersPerUnit = 1", '    upAxis = "Z"', ")",
        'def Scope "TribopipeFriction"', "{", "}", '    def Material "PinOnDisc" (',
        '        prepend apiSchemas = ["PhysicsMaterialAPI", "PhysxMaterialAPI"]', "    )",
        "    {", "    }", '    def Cube "Pin" (', '    def Cylinder "Disc" (',
        '        prepend apiSchemas = ["PhysicsCollisionAPI", "MaterialBindingAPI"]',
        "        rel material:binding:physics = </TribopipeFriction/PinOnDisc>",
        '        uniform token[] xformOpOrder = ["xformOp:translate"]',
        "        double size = 0.02", "        double3 xformOp:translate = (0, 0, 0.02)",
        '        uniform token axis = "Z"', "        double height = 0.02",
        "        double radius = 0.2", "        double3 xformOp:translate = (0, 0, 0)",
    }
    values: dict[str, object] = {}
    for line in lines[1:]:
        if not line or line.startswith("#") or line in fixed:
            continue
        key, _, value = line.strip().rpartition(" = ")
        if key == "float physics:staticFriction":
            values["static"] = float(value)
        elif key == "float physics:dynamicFriction":
            values["dynamic"] = float(value)
        elif key == "uniform token physxMaterial:frictionCombineMode":
            values["mode"] = ast.literal_eval(value)
        else:
            raise AssertionError(f"unexpected USD line {line!r}")
    return values


def urdf_friction(text: str) -> tuple[str, float]:
    """(link name, lateral friction) of a URDF we write: one robot, one link, and only the
    elements we write."""
    root = ET.fromstring(text.encode())
    assert root.tag == "robot"
    (link,) = list(root)
    assert link.tag == "link" and link.get("name") == root.get("name")
    assert [c.tag for c in link] == ["contact", "inertial", "collision"]
    (friction,) = list(link.find("contact"))
    assert friction.tag == "lateral_friction"
    return link.get("name"), float(friction.get("value"))


def sdf_friction(text: str) -> dict[str, tuple[float, float]]:
    """{link name: (mu_static, mu_dynamic)} of an SDFormat model we write."""
    drake = "{http://drake.mit.edu}"
    root = ET.fromstring(text.encode())
    assert root.tag == "sdf"
    (model,) = list(root)
    assert model.tag == "model"
    found = {}
    for link in model:
        assert link.tag == "link"
        assert [c.tag for c in link] == ["pose", "inertial", "collision"]
        props = link.find("collision").find(drake + "proximity_properties")
        assert [c.tag for c in props] == [drake + "mu_dynamic", drake + "mu_static"]
        found[link.get("name")] = (float(props.find(drake + "mu_static").text),
                                   float(props.find(drake + "mu_dynamic").text))
    return found
def engine_reading(entries: list[tuple[float | None, float, float]], p: float,
                   t: float | None) -> float:
    """μ as ABAQUS or Ansys reads a (temperature, pressure, μ) table: linear in pressure
    between rows at each table temperature, linear between temperatures, the end values
    held outside (the documented behaviour of both engines)."""
    import numpy as np

    temps = sorted({e[0] for e in entries if e[0] is not None})

    def at(temp: float | None) -> float:
        rows = sorted((e[1], e[2]) for e in entries if e[0] == temp)
        return float(np.interp(p, [r[0] for r in rows], [r[1] for r in rows]))

    if not temps or t is None:
        return at(temps[0] if temps else None)
    if t <= temps[0]:
        return at(temps[0])
    if t >= temps[-1]:
        return at(temps[-1])
    hi = next(i for i, v in enumerate(temps) if v > t)
    w = (t - temps[hi - 1]) / (temps[hi] - temps[hi - 1])
    return (1 - w) * at(temps[hi - 1]) + w * at(temps[hi])


def engine_reading_by_speed(entries: list[tuple[float | None, float, float, float]]
                            ) -> Callable[[float, float | None, float], float]:
    """μ as ABAQUS or Ansys reads a (temperature, pressure, slip rate, μ) table, as a
    function of (pressure, temperature, slip rate): linear in slip rate between rows at
    each pressure, then as :func:`engine_reading` over pressure and temperature (the end
    values held outside)."""
    import numpy as np

    by_row: dict[tuple[float | None, float], list[tuple[float, float]]] = {}
    for temp, pressure, slip, mu in entries:
        by_row.setdefault((temp, pressure), []).append((slip, mu))
    curves = {key: (np.array([r[0] for r in sorted(rows)]), np.array([r[1] for r in sorted(rows)]))
              for key, rows in by_row.items()}

    def reading(p: float, t: float | None, v: float) -> float:
        at_speed = [(temp, pressure, float(np.interp(v, slips, mus)))
                    for (temp, pressure), (slips, mus) in curves.items()]
        return engine_reading(at_speed, p, t)

    return reading
