#!/usr/bin/env python3
"""The README's component table matches the tree.

    readme_components.py SOURCE_DIR [README.md]

Reads the table under "## Components" of README.md (default: SOURCE_DIR/README.md). A row's first
cell names its area (`protocol/`, ...); a header named in a row as `name.hpp` is
include/endohaptics/<area>/name.hpp, one named `area/name.hpp` is include/endohaptics/area/name.hpp.
Checks, both ways:
  - every header the table names exists, and every public header (not under detail/) is named;
  - every program the table names (`endohaptics-...`) is a target of examples/ or benchmarks/
    (endohaptics_add_example or add_executable, not the test executables whose source is under
    tests/), and every such target is named.
Prints one "FAIL: README.md:LINE: ..." line per mismatch and a final "FAIL: ..." or "PASS: ...".
"""
import pathlib
import re
import sys

HEADER = re.compile(r"`([A-Za-z0-9_/]+\.hpp)`")
PROGRAM = re.compile(r"`(endohaptics-[a-z0-9-]+)`")
AREA = re.compile(r"^`([a-z_]+)/`$")
TARGET = re.compile(r"(?:endohaptics_add_example|add_executable)\(\s*(endohaptics-[a-z0-9-]+)([^\n]*)")


def table_rows(readme):
    """(line number, cells) of each body row of the table under "## Components"."""
    lines = readme.read_text(encoding="utf-8").splitlines()
    try:
        start = lines.index("## Components")
    except ValueError:
        return None
    rows = []
    for number, line in enumerate(lines[start + 1:], start + 2):
        if line.startswith("## "):
            break
        if not line.startswith("|"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] in ("area", "---") or set(cells[0]) <= set("-: "):
            continue
        rows.append((number, cells))
    return rows


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    source = pathlib.Path(sys.argv[1])
    readme = pathlib.Path(sys.argv[2]) if len(sys.argv) == 3 else source / "README.md"
    include = source / "include" / "endohaptics"
    rows = table_rows(readme)
    if not rows:
        print(f"FAIL: {readme.name}: no table under '## Components'")
        return 1

    failures = []
    named_headers, named_programs = {}, {}
    for number, cells in rows:
        match = AREA.match(cells[0])
        area = match.group(1) if match else ""
        text = " | ".join(cells[1:])
        for name in HEADER.findall(text):
            path = name if "/" in name or not area else f"{area}/{name}"
            named_headers.setdefault(path, number)
        for name in PROGRAM.findall(text):
            named_programs.setdefault(name, number)

    headers = {p.relative_to(include).as_posix() for p in include.rglob("*.hpp")
               if "detail" not in p.relative_to(include).parts}
    for path, number in sorted(named_headers.items()):
        if path not in headers:
            failures.append(f"{readme.name}:{number}: names {path}, which is not a public header "
                            f"under include/endohaptics/")
    for path in sorted(headers - named_headers.keys()):
        failures.append(f"{readme.name}: the component table does not name {path}")

    programs = set()
    for cmake in sorted([*source.glob("examples/**/CMakeLists.txt"), *source.glob("examples/**/*.cmake"),
                         source / "benchmarks" / "CMakeLists.txt"]):
        for name, rest in TARGET.findall(cmake.read_text(encoding="utf-8")):
            if "/tests/" not in rest:
                programs.add(name)
    for name, number in sorted(named_programs.items()):
        if name not in programs:
            failures.append(f"{readme.name}:{number}: names {name}, which no CMake file in "
                            f"examples/ or benchmarks/ builds")
    for name in sorted(programs - named_programs.keys()):
        failures.append(f"{readme.name}: the component table does not name the program {name}")

    for failure in failures:
        print("FAIL:", failure)
    if failures:
        print(f"FAIL: {len(failures)} mismatches between the component table and the tree")
        return 1
    print(f"PASS: the component table names all {len(headers)} public headers and "
          f"{len(programs)} programs, and nothing else")
    return 0


if __name__ == "__main__":
    sys.exit(main())
