#!/usr/bin/env python3
"""The codebase's form, checked (issue 40's targets), so that none of them slips back unseen.

    python3 tools/check_codebase.py [REPO_ROOT]     (ctest -R codebase_targets)

Each check prints what fails; the exit status is 1 when any does:
  - README.md has at most 200 lines and quotes no commit hash;
  - no source file (C++, Python, shell) has more than 600 lines;
  - at most 10 comment lines quote figures (timings, before -> after errors, counts), and none
    refers to a document outside the repository (docs/notes/ holds the figures);
  - one home per concept: only src/io/ply_reader.cc reads a PLY header, only
    src/mesh/disjoint_sets.h is a union-find, only src/registration/depth_image.cc builds the
    camera frame, only src/scene/yaml_reader.cc maps a YAML error to file and line;
  - file formats are parsed in src/io: no other file of src/ or tools/femreg opens a file for
    reading, but for a short allow-list of files that read something else (the machine's load,
    the scene's YAML text, ground truth CSV), each with its reason;
  - the developer guide's architecture page matches the code: its layer table names every
    module of src/ and solvers/ at the rank tests/layering_test.cc gives it, every path it
    names exists, and every C++ name it gives is in the sources.
"""
import os
import re
import sys

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
SOURCE_DIRS = ["src", "include", "solvers", "tools", "python", "bench", "fuzz", "tests", "examples"]
SOURCE_EXT = (".cc", ".h", ".cpp", ".hpp", ".py", ".sh")
README_LINES = 200
FILE_LINES = 600
FIGURE_LINES = 10

# A comment line that quotes a measurement (docs/notes/2026-11-28-figures-from-code-comments.md).
FIGURE = re.compile(
    r"[0-9] ?(mm|ms|%)? against [0-9]|[0-9]+ of [0-9]+ (frames|runs|cases|here|such)"
    r"|(^|[^A-Za-z0-9_.])[0-9.]+ ?(ms|us|µs|ns|s|min)([^A-Za-z0-9_]|$)|[0-9] ?-+> ?[0-9]"
    r"|[0-9] (against|vs\.?) [0-9]|[0-9.] ?x (faster|slower)|[0-9] times (faster|slower)"
    r"|[0-9] ?% (fewer|faster|slower|more|less)|[Mm]easured[^.]*[0-9]|[Ee]rrors? (of )?[0-9.]+ ?mm"
    r"|[0-9] ?mm (mean|error)|from [0-9.]+ to [0-9.]+ ?(mm|ms)|of [0-9]+ frames converged")
# A reference to a document the repository does not hold: the seed paper, the design notes
# that preceded the docs, a document of the shared folder beside the repository, or "the
# README" (the repository's is README.md, named so).
OUTSIDE = re.compile(
    r"seed (Section|eqs?\.|eq |'s)|[Ss]ection [0-9]|DESIGN\.md|STYLE\.md"
    r"|\.\./shared/\S*\.(md|pdf|txt|tex)\b|README(,|:| \")|the README\b(?!\.md)")
# A link into docs/ is the way a comment points to the method or a note: not a figure.
DOCS_LINK = re.compile(r"docs/[A-Za-z0-9_./#-]*")

failures = []


def fail(check, message):
    failures.append(f"{check}: {message}")


def rel(path):
    return os.path.relpath(path, ROOT)


def source_files():
    for top in SOURCE_DIRS:
        for dirpath, dirnames, filenames in os.walk(os.path.join(ROOT, top)):
            dirnames[:] = [d for d in dirnames if d not in ("fixtures", "__pycache__", "build")]
            for name in sorted(filenames):
                if name.endswith(SOURCE_EXT):
                    yield os.path.join(dirpath, name)


def read_lines(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        return f.read().splitlines()


def check_readme():
    lines = read_lines(os.path.join(ROOT, "README.md"))
    if len(lines) > README_LINES:
        fail("README", f"README.md has {len(lines)} lines (at most {README_LINES})")
    for i, line in enumerate(lines, 1):
        for token in re.findall(r"(?<![0-9A-Za-z/_.-])[0-9a-f]{7,40}(?![0-9A-Za-z_-])", line):
            if re.search(r"[0-9]", token) and re.search(r"[a-f]", token):
                fail("README", f"README.md:{i}: a commit hash? {token}")


def comment_lines(path, lines):
    """Each comment's text: C++ // comments, shell and Python # comments (not a #! line)."""
    cpp = path.endswith((".cc", ".h", ".cpp", ".hpp"))
    for i, line in enumerate(lines, 1):
        if cpp:
            k = line.find("//")
            if k >= 0:
                yield i, line[k:]
        elif re.match(r"\s*#", line) and not (i == 1 and line.startswith("#!")):
            yield i, line


def check_files():
    figures = []
    for path in source_files():
        lines = read_lines(path)
        if len(lines) > FILE_LINES:
            fail("file length", f"{rel(path)} has {len(lines)} lines (at most {FILE_LINES})")
        for i, text in comment_lines(path, lines):
            text = DOCS_LINK.sub("", text)
            if FIGURE.search(text):
                figures.append(f"{rel(path)}:{i}: {text.strip()}")
            if OUTSIDE.search(text):
                fail("outside documents", f"{rel(path)}:{i}: {text.strip()}")
    if len(figures) > FIGURE_LINES:
        fail("figures in comments",
             f"{len(figures)} comment lines quote figures (at most {FIGURE_LINES}; move them to a note):\n    "
             + "\n    ".join(figures))


# One home per concept: a line of C++ code (src, include, solvers, tools, python/src) that does
# the concept's work, the file it belongs in. The patterns are the way the home does it (so
# the home must match: the check cannot pass by no longer seeing it); a copy written the same
# way elsewhere fails.
ONE_HOME = [
    ("one PLY reader", re.compile(r'[=!]=\s*"end_header"|"end_header"\s*[=!]=|(find|compare|StartsWith)\([^)]*"end_header"'),
     os.path.join("src", "io", "ply_reader.cc")),
    ("one union-find", re.compile(r"iota\(\s*parent"), os.path.join("src", "mesh", "disjoint_sets.h")),
    ("one camera frame", re.compile(r"Vector3d\s+\w+\s*=\s*[\w.]*target\s*-\s*[\w.]*position\b"),
     os.path.join("src", "registration", "depth_image.cc")),
    ("one YAML-error mapping", re.compile(r"\.mark\.(line|column|is_null)\b"), os.path.join("src", "scene", "yaml_reader.cc")),
]


def check_one_home():
    found = {name: False for name, _, _ in ONE_HOME}
    for path in source_files():
        if not path.endswith((".cc", ".h")) or rel(path).split(os.sep)[0] in ("tests", "fuzz", "bench", "examples"):
            continue
        for i, line in enumerate(read_lines(path), 1):
            code = line.split("//")[0]
            for name, pattern, home in ONE_HOME:
                if not pattern.search(code):
                    continue
                if rel(path) == home:
                    found[name] = True
                else:
                    fail(name, f"{rel(path)}:{i} does what {home} does: {line.strip()}")
    for name, _, home in ONE_HOME:
        if not found[name]:
            fail(name, f"{home} no longer matches this check's pattern: update the check")


# Opening a file for reading: an input stream or fopen in a read mode (writers are not looked at).
READS_FILE = re.compile(r'\b(std::)?i?fstream\s*[\w({]|\bfopen\s*\([^;]*,\s*"r')
# The files of src/ outside src/io that read a file, each with why that is not a file format io
# should parse. Everything else that reads a file belongs in src/io.
READS_FILE_ALLOWED = {
    os.path.join("src", "parallel", "threads.cc"): "/proc/loadavg and /proc/self/task, the machine's load",
    os.path.join("src", "scene", "scene_parser.cc"): "the scene file's text, parsed by yaml-cpp",
    os.path.join("src", "eval", "ground_truth.cc"): "a dataset's ground truth CSV",
    os.path.join("src", "eval", "piece_errors.cc"): "a dataset's per-piece ground truth CSV",
    os.path.join("src", "eval", "forces.cc"): "a dataset's forces.csv and a run's stats.csv",
    os.path.join("src", "experiments", "experiment.cc"): "the bench / compare CSV that module writes",
    # The command line (tools/femreg) reads files through the library too; these parse their own.
    os.path.join("tools", "femreg", "eval_command.cc"): "femreg register's embedded-surface VTP (its points)",
    os.path.join("tools", "femreg", "cli_util.cc"): "a fracture dataset's events.csv, for the closing line",
    os.path.join("tools", "femreg", "fracture_data_command.cc"): "CalculiX's .dat output of the deck it writes",
}


def check_file_formats_in_io():
    reading = set()
    for path in source_files():
        r = rel(path)
        in_scope = r.startswith("src" + os.sep) or r.startswith(os.path.join("tools", "femreg") + os.sep)
        if not in_scope or r.startswith(os.path.join("src", "io") + os.sep):
            continue
        for i, line in enumerate(read_lines(path), 1):
            code = line.split("//")[0]
            if code.lstrip().startswith("#") or not READS_FILE.search(code):
                continue
            reading.add(r)
            if r not in READS_FILE_ALLOWED:
                fail("file formats in io", f"{r}:{i} reads a file outside src/io (a file format's "
                     f"parser belongs in src/io, or give the file a reason in READS_FILE_ALLOWED): {line.strip()}")
    for r in sorted(set(READS_FILE_ALLOWED) - reading):
        fail("file formats in io", f"{r} is allowed to read a file but no longer does: drop it from READS_FILE_ALLOWED")


def layering_ranks():
    text = open(os.path.join(ROOT, "tests", "layering_test.cc"), encoding="utf-8").read()
    table = text[text.index("kRank"):]
    table = table[:table.index("};")]
    return {m: int(r) for m, r in re.findall(r'\{"(\w+)",\s*(\d+)\}', table)}


def check_architecture():
    page = os.path.join(ROOT, "docs", "dev", "architecture.md")
    text = open(page, encoding="utf-8").read()
    ranks = layering_ranks()
    documented = {}
    for rank, modules in re.findall(r"^\|\s*(\d+)\s*\|\s*([^|]+)\|", text, re.M):
        for module in re.findall(r"`(\w+)`", modules):
            documented[module] = int(rank)
    modules = sorted(d for d in os.listdir(os.path.join(ROOT, "src")) if os.path.isdir(os.path.join(ROOT, "src", d)))
    for module in modules + ["solvers", "tools"]:
        if module not in documented:
            fail("architecture", f"module {module} is not in the layer table of docs/dev/architecture.md")
        elif module in ranks and ranks[module] != documented[module]:
            fail("architecture", f"module {module}: rank {documented[module]} on the page, "
                 f"{ranks[module]} in tests/layering_test.cc")
    for module in documented:
        if module not in ranks:
            fail("architecture", f"the page's module {module} is not in tests/layering_test.cc")

    all_files = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = [d for d in dirnames if not d.startswith(".") and d != "build"]
        all_files += [rel(os.path.join(dirpath, f)) for f in filenames]
    stems = {os.path.splitext(os.path.basename(f))[0] for f in all_files}
    code = ""
    for path in source_files():
        if path.endswith((".cc", ".h")) and not rel(path).startswith("tests"):
            code += open(path, encoding="utf-8", errors="replace").read()
    for token in sorted(set(re.findall(r"`([^`\n]+)`", text))):
        if "<" in token or " " in token:
            continue  # a pattern ("solvers/<name>/") or a phrase
        if "/" in token or re.search(r"\.(cc|h|md|py|sh)$", token):
            path = token.rstrip("/")
            found = any(os.path.exists(os.path.join(ROOT, base, path))
                        for base in ("", "src", "include", "solvers", "docs/dev"))
            found = found or (not token.endswith("/") and any(f.endswith("/" + path) for f in all_files))
            found = found or (path in stems or os.path.basename(path) in stems)  # scene/yaml_reader
            if not found:
                fail("architecture", f"the page names `{token}`, which is not in the repository")
        for name in re.findall(r"\b([A-Z][a-z0-9]+[A-Z][A-Za-z0-9]*)\b", token):  # CamelCase
            if not re.search(r"\b" + name + r"\b", code):
                fail("architecture", f"the page names {name} (in `{token}`), which the sources do not define")


check_readme()
check_files()
check_one_home()
check_file_formats_in_io()
check_architecture()
for f in failures:
    print(f)
print(f"check_codebase: {'FAILED, ' + str(len(failures)) + ' finding(s)' if failures else 'all targets met'}")
sys.exit(1 if failures else 0)
