#!/usr/bin/env python3
"""Keeps the stage graph of docs/architecture.md true: run by .ci/run, exits 1 on any break.

The table under "## Stage graph" in docs/architecture.md lists each stage of src/lightvol/ and the
stages it may include. This script checks that the table is acyclic and that every #include in
src/, cli/ and tests/ keeps to it:

  1. a file of stage S includes <lightvol/T/...> only for T = S or T listed for S;
  2. nothing outside stage T includes T's internal headers (<lightvol/T/detail/...>), except tests
     and except core/detail/, the library-internal helpers every stage may use;
  3. a public header (not under detail/) includes only the standard library, POSIX, public
     lightvol headers and, in the gl stage, the GL headers: an installed header never needs a
     private dependency;
  4. the library uses rooted includes only (no "quoted" includes in src/);
  5. every folder of src/lightvol/ is a stage of the table, and every stage a folder.

Each break is printed as FILE:LINE: the include and the rule it breaks.
Usage: tools/check_includes.py [REPO_ROOT]
       tools/check_includes.py --self-test   (plants each kind of break in a scratch tree and
                                              fails unless every one is reported)
"""
import os
import re
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
STAGE_ROW = re.compile(r"^\|\s*`([a-z_0-9]+)`\s*\|([^|]*)\|")
GL_HEADERS = re.compile(r"^(GL|EGL|KHR)/")


def read_table():
    path = os.path.join(ROOT, "docs", "architecture.md")
    allowed, in_graph = {}, False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("## "):
                in_graph = line.strip() == "## Stage graph"
                continue
            m = STAGE_ROW.match(line) if in_graph else None
            if m:
                allowed[m.group(1)] = set(re.findall(r"`([a-z_0-9]+)`", m.group(2)))
    if not allowed:
        sys.exit(f"{path}: no stage table under '## Stage graph'")
    return allowed


def find_cycle(allowed):
    state = {}

    def visit(stage, path):
        state[stage] = "open"
        for up in sorted(allowed.get(stage, ())):
            if state.get(up) == "open":
                return path + [stage, up]
            if up not in state:
                cycle = visit(up, path + [stage])
                if cycle:
                    return cycle
        state[stage] = "done"
        return None

    for stage in sorted(allowed):
        if stage not in state:
            cycle = visit(stage, [])
            if cycle:
                return cycle
    return None


def source_files(top):
    for base, dirs, files in os.walk(os.path.join(ROOT, top)):
        dirs[:] = sorted(d for d in dirs if d not in ("corpus", "node_modules"))
        for name in sorted(files):
            if name.endswith((".h", ".hpp", ".cpp", ".cc")):
                yield os.path.join(base, name)


def main():
    allowed = read_table()
    errors = []
    for stage, ups in sorted(allowed.items()):
        for up in sorted(ups - set(allowed)):
            errors.append(f"docs/architecture.md: stage '{stage}' may include '{up}', which is no stage")
    cycle = find_cycle(allowed)
    if cycle:
        errors.append("docs/architecture.md: the stage graph has a cycle: " + " -> ".join(cycle))

    lib = os.path.join(ROOT, "src", "lightvol")
    folders = {d for d in os.listdir(lib) if os.path.isdir(os.path.join(lib, d))}
    for d in sorted(folders - set(allowed)):
        errors.append(f"src/lightvol/{d}/: a folder that docs/architecture.md's stage graph does not list")
    for d in sorted(set(allowed) - folders):
        errors.append(f"docs/architecture.md: stage '{d}' has no folder src/lightvol/{d}/")

    for top in ("src", "cli", "tests"):
        for path in source_files(top):
            rel = os.path.relpath(path, ROOT)
            parts = rel.split(os.sep)
            stage = parts[2] if top == "src" and len(parts) > 3 else None
            public_header = top == "src" and rel.endswith(".h") and "detail" not in parts
            with open(path, encoding="utf-8", errors="replace") as f:
                for number, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    quoted, name = m.group(1) == '"', m.group(2)
                    closer = '"' if quoted else ">"
                    where = f"{rel}:{number}: #include {m.group(1)}{name}{closer}"
                    if top == "src" and quoted:
                        errors.append(f"{where}: the library includes rooted paths only (<lightvol/...>)")
                        continue
                    target = re.match(r"lightvol/([a-z_0-9]+)/(detail/)?", name)
                    if target:
                        t_stage, t_detail = target.group(1), bool(target.group(2))
                        if t_stage not in allowed:
                            errors.append(f"{where}: '{t_stage}' is no stage")
                        elif stage and t_stage != stage and t_stage not in allowed.get(stage, ()):
                            errors.append(f"{where}: stage '{stage}' may not include stage '{t_stage}' "
                                          f"(it may include: {', '.join(sorted(allowed[stage])) or 'nothing'})")
                        if t_detail and top != "tests" and t_stage != stage and not (stage and t_stage == "core"):
                            errors.append(f"{where}: '{t_stage}/detail/' is internal to stage '{t_stage}'")
                        if t_detail and public_header:
                            errors.append(f"{where}: a public header includes an internal one (it is not installed)")
                    elif public_header and not quoted:
                        system = re.fullmatch(r"[a-z_0-9]+(\.h)?|(sys|arpa|netinet|linux)/[a-z_0-9/]+\.h", name)
                        if not system and not (stage == "gl" and GL_HEADERS.match(name)):
                            errors.append(f"{where}: a public header includes a private dependency")
    for e in errors:
        print(e)
    if errors:
        print(f"check_includes: {len(errors)} break(s) of the stage graph in docs/architecture.md")
        return 1
    print(f"check_includes: {len(allowed)} stages, acyclic; every include keeps to the graph")
    return 0


SELF_TEST_TABLE = """## Stage graph
| stage | may include | what it holds |
|---|---|---|
| `core` | | |
| `light` | `core` | |
| `gl` | `core` | |
"""

# Each planted file and the words its break must be reported with; the first two are clean.
SELF_TEST_FILES = {
    "src/lightvol/core/a.h": ("#include <vector>\n", None),
    "src/lightvol/light/b.cpp": ("#include <lightvol/core/a.h>\n#include <lightvol/core/detail/x.h>\n", None),
    "src/lightvol/core/c.cpp": ("#include <lightvol/light/b.h>\n", "stage 'core' may not include stage 'light'"),
    "src/lightvol/gl/d.cpp": ("#include <lightvol/light/detail/y.h>\n", "is internal to stage 'light'"),
    "src/lightvol/light/e.h": ("#include <nlohmann/json.hpp>\n", "a public header includes a private dependency"),
    "src/lightvol/light/f.h": ("#include <lightvol/light/detail/y.h>\n", "a public header includes an internal one"),
    "src/lightvol/light/g.cpp": ('#include "b.h"\n', "rooted paths only"),
    "src/lightvol/extra/h.cpp": ("\n", "a folder that docs/architecture.md's stage graph does not list"),
    "cli/i.cpp": ("#include <lightvol/core/detail/x.h>\n", "is internal to stage 'core'"),
}


def self_test():
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "docs"))
        with open(os.path.join(root, "docs", "architecture.md"), "w") as f:
            f.write(SELF_TEST_TABLE)
        for rel, (text, _) in SELF_TEST_FILES.items():
            os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w") as f:
                f.write(text)
        os.makedirs(os.path.join(root, "tools"))
        script = os.path.join(root, "tools", "check_includes.py")
        with open(__file__) as src, open(script, "w") as dst:
            dst.write(src.read())
        run = subprocess.run([sys.executable, script], capture_output=True, text=True)
        failures = []
        if run.returncode != 1:
            failures.append(f"exit status {run.returncode}, expected 1")
        for rel, (_, words) in SELF_TEST_FILES.items():
            lines = [l for l in run.stdout.splitlines()
                     if l.startswith(rel) or l.startswith(os.path.dirname(rel) + "/:")]
            if words and not any(words in l for l in lines):
                failures.append(f"{rel}: not reported as '{words}'")
            if not words and lines:
                failures.append(f"{rel}: reported though it keeps the graph: {lines}")
        with open(os.path.join(root, "docs", "architecture.md"), "a") as f:
            f.write("| `cycle` | `cycle2` | |\n| `cycle2` | `cycle` | |\n")
        run = subprocess.run([sys.executable, script], capture_output=True, text=True)
        if "the stage graph has a cycle: cycle -> cycle2 -> cycle" not in run.stdout:
            failures.append("a cycle in the table was not reported: " + run.stdout)
    for f in failures:
        print("self-test:", f)
    print("check_includes self-test:", "failed" if failures else f"all {len(SELF_TEST_FILES) + 1} cases as expected")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(self_test() if sys.argv[1:] == ["--self-test"] else main())
