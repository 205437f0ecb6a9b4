#!/usr/bin/env python3
"""docs/README.md indexes every page of docs/, and every page it links to exists.

    docs_index.py SOURCE_DIR [INDEX.md]

INDEX.md defaults to SOURCE_DIR/docs/README.md; its links are relative to SOURCE_DIR/docs/. Every
Markdown page under docs/ (docs/README.md itself aside) must be linked from the index, and every
relative link of the index to a .md page (an #anchor aside) must name a page that exists.
Prints one "FAIL: ..." line per mismatch and a final "FAIL: ..." or "PASS: ...".
"""
import pathlib
import re
import sys

LINK = re.compile(r"\]\(([^)#\s]+\.md)(?:#[^)]*)?\)")


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    docs = pathlib.Path(sys.argv[1]) / "docs"
    index = pathlib.Path(sys.argv[2]) if len(sys.argv) == 3 else docs / "README.md"
    failures = []
    linked = set()
    for number, line in enumerate(index.read_text(encoding="utf-8").splitlines(), 1):
        for target in LINK.findall(line):
            if "://" in target:
                continue
            path = (docs / target).resolve()
            if not path.is_file():
                failures.append(f"{index.name}:{number}: links {target}, which does not exist")
            linked.add(path)
    pages = sorted(p for p in docs.rglob("*.md") if p.resolve() != (docs / "README.md").resolve())
    for page in pages:
        if page.resolve() not in linked:
            failures.append(f"{index.name}: does not index docs/{page.relative_to(docs).as_posix()}")
    for failure in failures:
        print("FAIL:", failure)
    if failures:
        print(f"FAIL: {len(failures)} mismatches between the index and docs/")
        return 1
    print(f"PASS: {index.name} indexes all {len(pages)} pages of docs/, and every page it links exists")
    return 0


if __name__ == "__main__":
    sys.exit(main())
