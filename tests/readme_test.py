#!/usr/bin/env python3
"""Checks that README.md stays a guide a newcomer reads through.

Fails, with one line per finding, when:
  - README.md is longer than MAX_LINES: it keeps one example of each feature; the detail goes
    to the man pages (man/) and the measurements to the tests' READMEs beside their commands;
  - a relative link of README.md names a file that does not exist, or an anchor (#section) that
    is not a heading of the Markdown file it names.
Usage: readme_test.py [PROJECT_SOURCE_DIR]
"""
import os
import re
import sys

MAX_LINES = 350

LINK = re.compile(r"\]\(([^)\s]+)\)")
HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$")


def anchor(heading):
    """The anchor GitHub gives a Markdown heading: lower case, punctuation dropped, spaces to -."""
    text = re.sub(r"[^\w\- ]", "", heading.lower())
    return text.replace(" ", "-")


def anchors(path):
    found, fenced = set(), False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("```"):
                fenced = not fenced
            m = None if fenced else HEADING.match(line)
            if m:
                found.add(anchor(m.group(1)))
    return found


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    readme = os.path.join(root, "README.md")
    with open(readme, encoding="utf-8") as f:
        lines = f.read().splitlines()
    findings = []
    if len(lines) > MAX_LINES:
        findings.append(f"README.md has {len(lines)} lines, more than {MAX_LINES}: keep one "
                        "example per feature and move the detail to the man pages (man/) and the "
                        "measurements, with their commands, to the tests' READMEs")

    links = 0
    for number, line in enumerate(lines, 1):
        for target in LINK.findall(line):
            if re.match(r"^[a-z]+:", target):
                continue  # https:, mailto:
            links += 1
            path, _, section = target.partition("#")
            file = os.path.normpath(os.path.join(root, path)) if path else readme
            if not os.path.exists(file):
                findings.append(f"README.md:{number}: links to {path}, which does not exist")
            elif section and file.endswith(".md") and section not in anchors(file):
                findings.append(f"README.md:{number}: links to {target}, but "
                                f"{os.path.relpath(file, root)} has no heading #{section}")

    for finding in findings:
        print("readme_test: " + finding, file=sys.stderr)
    if findings:
        return 1
    print(f"readme_test: README.md has {len(lines)} lines (at most {MAX_LINES}); "
          f"its {links} relative links resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main())
