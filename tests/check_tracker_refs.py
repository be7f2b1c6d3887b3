#!/usr/bin/env python3
"""Fails on references to a tracker in code, docs and tests (docs/style.md: "Design docs hold
decisions, named, not tracker numbers"): the word issue, task or ticket followed by a number, a bare
#<number>, and "the issue" as a name for the work. A comment or a doc says what and why instead.

Not references: hex colours ("#444", fill="#000000"), preprocessor lines (#include, #define, #pragma),
Markdown headings, HTML entities (&#39;), URL fragments (page#1) and assembler immediates
(str r2, [r0], #4). Prints file:line of each hit; exit status 1 when there is one.

Usage: check_tracker_refs.py SOURCE_DIR
"""
import os
import re
import sys

ROOTS = ["firmware_lib", "protocol", "host_tools", "tests", "docs", "README.md", "CMakeLists.txt", ".ci"]

# "issue 12", "Issue-12", "task #3", "ticket 7".
WORD_NUMBER = re.compile(r"\b(?:issue|task|ticket)s?[ -]?#?[0-9]+\b", re.IGNORECASE)
# "the issue" as the name of a piece of work ("the issue's goal", "what the issue describes").
THE_ISSUE = re.compile(r"\bthe issue\b", re.IGNORECASE)
# "#12": after the start of the line, a space or an opening bracket, and a whole number (not the
# start of a hex colour such as #56B4E9 or of a word).
HASH_NUMBER = re.compile(r"(?:^|(?<=[\s(\[]))#([0-9]+)(?![\w.])")
# What a "#<digits>" may follow without being a reference: an assembler operand and a comma (an
# immediate), or ':' / '=' (a colour value).
NOT_REFERENCE_BEFORE = re.compile(r"(?:(?:\]|%[0-9]+|\b[rRxXwWsSdDqQvV][0-9]+|\b(?:sp|lr|pc|fp))\s*,|[:=])\s*$")


def hits_in_line(line):
    """The tracker references in one line of text, as the matched strings."""
    found = [m.group(0) for m in WORD_NUMBER.finditer(line)]
    found += [m.group(0) for m in THE_ISSUE.finditer(line)]
    for m in HASH_NUMBER.finditer(line):
        if not NOT_REFERENCE_BEFORE.search(line[: m.start()]):
            found.append(m.group(0))
    return found


def self_test():
    """The pattern's own cases, so that a change to it is seen to keep them."""
    must_hit = [
        "see issue 36 for the table",
        "(issue-13 branch)",
        "the issue's goal",
        "task 4 adds it",
        "fixed in #123",
        "(#7)",
        "- #42 follow-up",
    ]
    must_pass = [
        "#include <cstdint>",
        "#define GEOJCBB_X 1",
        "#pragma once",
        "## Licence",
        "# 1. a numbered comment",
        '"str r2, [r0], #4\\n\\t"',
        '"subs %0, %0, #1\\n\\t"',
        'stroke="#444" fill="#000000"',
        "color: #444;",
        'svg::Style::kLine, "#56B4E9"',
        "&#39; an entity",
        "docs/protocol.md#1-frames",
        "tissue 3 and multitask 4",
        "issues are values",
    ]
    bad = [s for s in must_hit if not hits_in_line(s)] + [s for s in must_pass if hits_in_line(s)]
    for s in bad:
        print(f"check_tracker_refs.py: the pattern is wrong on: {s}")
    return not bad


def text_files(root):
    if os.path.isfile(root):
        yield root
        return
    for d, dirs, files in os.walk(root):
        dirs[:] = sorted(x for x in dirs if x not in (".git", "build", "__pycache__"))
        for f in sorted(files):
            yield os.path.join(d, f)


def read_text(path):
    """The file's lines, or None for a binary file (a fuzz corpus entry, an image)."""
    with open(path, "rb") as f:
        data = f.read()
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        return None


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    if not self_test():
        return 1
    src = sys.argv[1]
    hits = 0
    files = 0
    for root in ROOTS:
        for path in text_files(os.path.join(src, root)):
            if os.path.samefile(path, __file__):
                continue  # this file spells the patterns out
            lines = read_text(path)
            if lines is None:
                continue
            files += 1
            for n, line in enumerate(lines, 1):
                for h in hits_in_line(line):
                    print(f"{os.path.relpath(path, src)}:{n}: tracker reference '{h}': say what and why instead")
                    hits += 1
    print(f"{files} files scanned, {hits} tracker references")
    return 1 if hits else 0


if __name__ == "__main__":
    sys.exit(main())
