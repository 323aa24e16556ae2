#!/usr/bin/env python3
"""Writes one MyST page per public header (include/femreg/*.h) for the C++ API reference.

The headers document themselves in plain // comments, which Doxygen does not read, so each
page is the header's opening comment as prose and the header itself as a listing. Run by
tools/docs.sh:  docs_api_pages.py INCLUDE_DIR OUT_DIR
"""
import pathlib
import sys


def opening_comment(text):
    """The header's first comment block, without the include guard or the '// name.h -'."""
    lines = []
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("//") and stripped[2:].strip():
            lines.append(stripped[2:].strip())
        elif lines:
            break  # the first paragraph only (a bare // ends it)
    if lines and " - " in lines[0] and lines[0].split(" - ", 1)[0].endswith(".h"):
        lines[0] = lines[0].split(" - ", 1)[1]
    prose = " ".join(lines).strip()
    return prose[:1].upper() + prose[1:] if prose else ""


def main():
    include_dir, out_dir = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    out_dir.mkdir(parents=True, exist_ok=True)
    headers = sorted(include_dir.glob("*.h"))
    written = set()
    for header in headers:
        page = out_dir / f"{header.stem}.md"
        rel = pathlib.Path("../../..") / header.relative_to(include_dir.parents[1])
        text = header.read_text(encoding="utf-8")
        body = (f"# femreg/{header.name}\n\n{opening_comment(text)}\n\n"
                f"```{{literalinclude}} {rel.as_posix()}\n:language: cpp\n```\n")
        if not page.exists() or page.read_text(encoding="utf-8") != body:
            page.write_text(body, encoding="utf-8")
        written.add(page.name)
    for stale in out_dir.glob("*.md"):
        if stale.name not in written:
            stale.unlink()


if __name__ == "__main__":
    main()
