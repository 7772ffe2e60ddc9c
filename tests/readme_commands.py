#!/usr/bin/env python3
"""Runs every csgvox command the README shows, and checks the docs' links.

Usage: readme_commands.py CSGVOX_BINARY SOURCE_DIR [--no-step]

The convention (docs/development.md, "The README's commands are tested"):

* a command is a line of a fenced ```sh block of README.md, or a part of
  such a line between `&&`, that starts with `csgvox ` or `build/app/csgvox `;
  it is run with CSGVOX_BINARY in its place;
* the commands run one after another, in the README's order, in a temporary
  folder holding a copy of the files a fresh clone has under data/ (the
  files `git ls-files data` lists; the whole folder when git cannot list
  them), so a command that needs a file the repository does not hold fails;
* each must exit 0 (within 300 s); a main job (`csgvox SCAN ...`, no
  sub-command) must leave its output files in its -o folder (preview.png
  not with --no-preview; tree.step not with --no-step, for a build without
  OpenCASCADE);
* every relative link of README.md and docs/*.md must name an existing file,
  and an existing heading when it has a #fragment.

Exit status 0 when all hold; otherwise 1, with one line per failure.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SUBCOMMANDS = {"detect", "sample", "render", "eval", "import-gp", "compare", "batch"}
PREFIXES = ("csgvox ", "build/app/csgvox ")
JOB_FILES = ["tree.json", "tree.scad", "tree.txt", "tree.csg", "tree.step", "preview.png",
             "mesh.ply", "report.json"]
# Options of the main job that take no value (every other option takes one).
JOB_FLAGS = {"-q", "--quiet", "--no-refine-thin", "--finish", "--no-finish", "--no-preview",
             "--no-separators", "--partition"}
TIMEOUT_S = 300


def sh_blocks(markdown):
    """The lines of every fenced ```sh block, in order."""
    lines, language = [], None  # language: None outside a block, else the block's ("" if none)
    for line in markdown.splitlines():
        fence = line.strip()
        if fence.startswith("```"):
            language = fence[3:].strip() if language is None else None
            continue
        if language == "sh":
            lines.append(line)
    return lines


def readme_commands(markdown):
    """The csgvox commands of the README's sh blocks, as argument lists (the binary left out)."""
    commands = []
    for line in sh_blocks(markdown):
        for part in line.split("&&"):
            part = part.strip()
            if part.startswith(PREFIXES):
                words = shlex.split(part, comments=True)
                commands.append((part, words[1:]))
    return commands


def job_output(args):
    """The output folder of a main-job command, or None for a sub-command."""
    if not args or args[0] in SUBCOMMANDS:
        return None
    out, scan, i = None, None, 0
    while i < len(args):
        a = args[i]
        if a in ("-o", "--output"):
            out = args[i + 1]
            i += 2
        elif a.startswith("--output="):
            out = a.split("=", 1)[1]
            i += 1
        elif a.startswith("-"):
            i += 1 if (a in JOB_FLAGS or "=" in a) else 2
        else:
            scan = scan or a
            i += 1
    if out is None and scan is not None:
        out = str(Path(scan).parent / (Path(scan).stem + "-csgvox"))
    return out


def copy_data(source, work):
    """Copies what a fresh clone holds under data/ into work/data."""
    try:
        listed = subprocess.run(["git", "-C", str(source), "ls-files", "-z", "data"],
                                capture_output=True, check=True).stdout
        files = [f for f in listed.decode().split("\0") if f]
    except (OSError, subprocess.CalledProcessError):
        files = []
    if not files:
        shutil.copytree(source / "data", work / "data")
        return
    for f in files:
        target = work / f
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source / f, target)


def without_code_blocks(markdown):
    return re.sub(r"^```.*?^```", "", markdown, flags=re.S | re.M)


def anchors(markdown):
    """The anchors GitHub gives the headings of a Markdown page."""
    seen, result = {}, set()
    for line in without_code_blocks(markdown).splitlines():
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        slug = re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        result.add(slug if n == 0 else f"{slug}-{n}")
    return result


def broken_links(source):
    """Relative links of README.md and docs/*.md to a missing file or heading."""
    failures = []
    pages = [source / "README.md"] + sorted((source / "docs").glob("*.md"))
    link = re.compile(r"\]\(([^)\s]+)\)")
    for page in pages:
        text = without_code_blocks(page.read_text(encoding="utf-8"))
        for target in link.findall(text):
            if re.match(r"^[a-z]+:", target):
                continue
            path, _, fragment = target.partition("#")
            linked = page.parent / path if path else page
            if not linked.exists():
                failures.append(f"{page.relative_to(source)}: link to missing file {target}")
            elif fragment and linked.suffix == ".md" and \
                    fragment not in anchors(linked.read_text(encoding="utf-8")):
                failures.append(f"{page.relative_to(source)}: link to missing heading {target}")
    return failures


def main():
    if len(sys.argv) < 3:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    binary = Path(sys.argv[1]).resolve()
    source = Path(sys.argv[2]).resolve()
    no_step = "--no-step" in sys.argv[3:]
    failures = broken_links(source)
    commands = readme_commands((source / "README.md").read_text(encoding="utf-8"))
    if not commands:
        failures.append("README.md: no csgvox command in a ```sh block")
    jobs = 0
    with tempfile.TemporaryDirectory(prefix="csgvox-readme-") as tmp:
        work = Path(tmp)
        copy_data(source, work)
        for text, args in commands:
            try:
                run = subprocess.run([str(binary)] + args, cwd=work, capture_output=True,
                                     text=True, timeout=TIMEOUT_S)
            except subprocess.TimeoutExpired:
                failures.append(f"{text}: still running after {TIMEOUT_S} s")
                continue
            status = "ok" if run.returncode == 0 else f"exit {run.returncode}"
            print(f"[{status}] {text}", flush=True)
            if run.returncode != 0:
                tail = (run.stderr.strip().splitlines() or [""])[-1]
                failures.append(f"{text}: exit {run.returncode}: {tail}")
                continue
            out = job_output(args)
            if out is None:
                continue
            jobs += 1
            expected = [f for f in JOB_FILES
                        if not (f == "preview.png" and "--no-preview" in args)
                        and not (f == "tree.step" and no_step)]
            missing = [f for f in expected if not (work / out / f).is_file()]
            if missing:
                failures.append(f"{text}: missing in {out}: {', '.join(missing)}")
    if commands and jobs == 0:
        failures.append("README.md: no main-job command (csgvox SCAN ...) in a ```sh block")
    for f in failures:
        print(f"FAILED: {f}", file=sys.stderr)
    print(f"{len(commands)} commands, {jobs} main jobs, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
