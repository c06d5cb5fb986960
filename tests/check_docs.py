#!/usr/bin/env python3
"""Checks the manual's links and runs its runnable blocks (Python 3 standard library only).

  check_docs.py links SOURCE_DIR
      Fails, naming each, where
      - a markdown link in README.md, docs/*.md or bench/README.md points to a file that does not
        exist, or to an #anchor that is not a heading of that file (GitHub's anchors: lowercase,
        spaces to '-', punctuation dropped);
      - a code comment (or any text in the sources) names a section in the form
            docs/PAGE.md, "Heading"      or      bench/README.md, "Heading"
        and PAGE has no such heading. "Heading" is a heading's text, or the part of it before its
        first ':' or ' (' ("Notched strength" names "Notched strength: the hole plate to failure").

  check_docs.py runnable SOURCE_DIR PLYDEM_DIR
      Runs every fenced block of README.md, docs/*.md and bench/README.md whose info string is
      `bash runnable` (or `sh runnable`, `python runnable`), each in a fresh temporary directory
      with PLYDEM_DIR first on PATH, `build` there a link to PLYDEM_DIR and `experiments` and
      `examples` links to the source tree's; fails naming each block that exits non-zero.
"""
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

PAGES_GLOBS = ["README.md", "docs/*.md", "bench/README.md"]
SOURCE_DIRS = ["core", "solvers", "contacts", "strategies", "packings", "experiments", "tests",
               "python", "bench", "scripts", "examples", "cmake", ".ci"]
SOURCE_FILES = ["CMakeLists.txt"]
SOURCE_SUFFIXES = {".hpp", ".cpp", ".h", ".cu", ".cuh", ".py", ".cmake", ".txt", ".toml", ".sh",
                   ".in", ""}
POINTER = re.compile(r'((?:docs/[A-Za-z0-9_.-]+|bench/README)\.md),\s+\\?"([^"\\]+)\\?"')
FENCE = re.compile(r"^(\s*)(```+|~~~+)(.*)$")
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def pages(root):
    found = []
    for pattern in PAGES_GLOBS:
        found += sorted(root.glob(pattern))
    return found


def split_fences(text):
    """Yields (line_number, line, in_fence, info) for each line; info is the open fence's."""
    fence = None
    info = ""
    for number, line in enumerate(text.split("\n"), 1):
        match = FENCE.match(line)
        if fence is None and match:
            fence, info = match.group(2), match.group(3).strip()
            yield number, line, True, info
            continue
        if fence is not None and match and match.group(2).startswith(fence[0]) \
                and len(match.group(2)) >= len(fence) and not match.group(3).strip():
            yield number, line, True, info
            fence = None
            continue
        yield number, line, fence is not None, info


def headings(path):
    """The headings' texts of a markdown file, outside fenced blocks."""
    result = []
    for _, line, in_fence, _ in split_fences(path.read_text(encoding="utf-8")):
        if in_fence:
            continue
        match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if match:
            result.append(match.group(1))
    return result


def anchor(heading):
    """GitHub's anchor of a heading: markup dropped, lowercase, punctuation dropped, ' ' -> '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)   # links keep their text
    text = text.replace("`", "").lower()
    text = re.sub(r"[^\w\- ]", "", text)                          # \w keeps letters of any script
    return text.replace(" ", "-")


def anchors(path):
    seen = {}
    result = set()
    for heading in headings(path):
        base = anchor(heading)
        count = seen.get(base, 0)
        result.add(base if count == 0 else f"{base}-{count}")
        seen[base] = count + 1
    return result


def strip_code_spans(line):
    return re.sub(r"(`+)(?:(?!\1).)+?\1", "", line)


def check_links(root):
    problems = []
    for page in pages(root):
        relative = page.relative_to(root)
        for number, line, in_fence, _ in split_fences(page.read_text(encoding="utf-8")):
            if in_fence:
                continue
            for match in LINK.finditer(strip_code_spans(line)):
                target = match.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):       # http:, https:, mailto:
                    continue
                file_part, _, fragment = target.partition("#")
                destination = (page.parent / file_part).resolve() if file_part else page
                where = f"{relative}:{number}: link '{target}'"
                if not destination.exists():
                    problems.append(f"{where}: no file {os.path.relpath(destination, root)}")
                    continue
                if fragment:
                    if destination.suffix != ".md":
                        problems.append(f"{where}: an #anchor into a file that is not markdown")
                    elif fragment not in anchors(destination):
                        problems.append(f"{where}: {os.path.relpath(destination, root)} has no "
                                        f"heading with the anchor #{fragment}")
    return problems


def source_files(root):
    for name in SOURCE_FILES:
        if (root / name).is_file():
            yield root / name
    for directory in SOURCE_DIRS:
        base = root / directory
        if not base.is_dir():
            continue
        for path in sorted(base.rglob("*")):
            if path.is_file() and path.suffix in SOURCE_SUFFIXES and "corpus" not in path.parts \
                    and path.resolve() != pathlib.Path(__file__).resolve():
                yield path
    for page in pages(root):
        yield page


def names_heading(name, page_headings):
    for heading in page_headings:
        plain = heading.replace("`", "")
        shorter = {plain, plain.split(" (")[0], plain.split(":")[0]}
        if name.replace("`", "") in {s.strip() for s in shorter}:
            return True
    return False


def check_pointers(root):
    problems = []
    count = 0
    cache = {}
    for path in source_files(root):
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue
        # A pointer may wrap onto the next comment line: join lines, dropping comment leaders.
        joined = re.sub(r"\n\s*(?://+|#+|\*)?\s*", " ", text)
        # ... and onto the next string literal of a C++ or CMake string: "... \"Strategies " "in
        # Python\"" is one pointer.
        joined = re.sub(r'(?<!\\)"\s+"', "", joined)
        for match in POINTER.finditer(joined):
            page, name = match.group(1), " ".join(match.group(2).split())
            count += 1
            target = root / page
            where = f"{path.relative_to(root)}: {page}, \"{name}\""
            if not target.is_file():
                problems.append(f"{where}: no file {page}")
                continue
            if page not in cache:
                cache[page] = headings(target)
            if not names_heading(name, cache[page]):
                problems.append(f"{where}: {page} has no such heading")
    return problems, count


def runnable_blocks(root):
    blocks = []
    for page in pages(root):
        current = None
        for number, line, in_fence, info in split_fences(page.read_text(encoding="utf-8")):
            words = info.split()
            marked = in_fence and len(words) >= 2 and "runnable" in words[1:]
            if current is None and marked and FENCE.match(line):
                current = {"where": f"{page.relative_to(root)}:{number}", "language": words[0],
                           "lines": []}
            elif current is not None and FENCE.match(line) and in_fence:
                blocks.append(current)
                current = None
            elif current is not None:
                current["lines"].append(line)
    return blocks


def run_blocks(root, plydem_dir):
    failures = []
    blocks = runnable_blocks(root)
    if not blocks:
        return ["no block is marked runnable (```bash runnable)"]
    environment = dict(os.environ)
    environment["PATH"] = f"{plydem_dir}{os.pathsep}{environment.get('PATH', '')}"
    for block in blocks:
        with tempfile.TemporaryDirectory(prefix="plydem_docs_") as directory:
            work = pathlib.Path(directory)
            (work / "build").symlink_to(plydem_dir, target_is_directory=True)
            for name in ("experiments", "examples"):
                if (root / name).exists():
                    (work / name).symlink_to(root / name, target_is_directory=True)
            script = "\n".join(block["lines"]) + "\n"
            if block["language"] in ("bash", "sh", "shell", "console"):
                command = ["bash", "-euo", "pipefail", "-c", script]
            elif block["language"] in ("python", "py", "python3"):
                command = [sys.executable, "-c", script]
            else:
                failures.append(f"{block['where']}: runnable block in '{block['language']}', "
                                "which this test cannot run")
                continue
            start = time.monotonic()
            done = subprocess.run(command, cwd=work, env=environment, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
            seconds = time.monotonic() - start
            print(f"{block['where']}: exit {done.returncode}, {seconds:.1f} s")
            if done.returncode != 0:
                tail = "\n".join(done.stdout.splitlines()[-20:])
                failures.append(f"{block['where']}: exited {done.returncode}:\n{tail}")
    return failures


def main(argv):
    if len(argv) < 3 or argv[1] not in ("links", "runnable") \
            or (argv[1] == "runnable" and len(argv) < 4):
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(argv[2]).resolve()
    if argv[1] == "links":
        problems = check_links(root)
        pointer_problems, count = check_pointers(root)
        problems += pointer_problems
        print(f"{len(pages(root))} pages, {count} section pointers in the sources")
    else:
        problems = run_blocks(root, pathlib.Path(argv[3]).resolve())
    for problem in problems:
        print(f"FAIL {problem}")
    if problems:
        print(f"{len(problems)} problem(s)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
