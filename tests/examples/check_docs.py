#!/usr/bin/env python3
"""Keeps the code examples of README.md and docs/*.md compiled or run: every ```cpp, ```c and
```python block must follow a marker line naming where it comes from, and equal it:

  <!-- example: tests/examples/associate.cpp -->   the block is the lines between the file's
                                                    "[doc]" and "[/doc]" marker lines (the file
                                                    is built and run by CTest)
  <!-- excerpt: path/to/header.hpp -->             the block's text stands in that file (a
                                                    declaration quoted from the code; blanks and
                                                    a last ";" aside)

usage: check_docs.py ROOT [--update]   (--update rewrites example blocks from their files)
"""
import glob
import os
import re
import sys

LANGS = ("cpp", "c", "python")
MARK = re.compile(r"^<!-- (example|excerpt): (\S+) -->\s*$")


def region(path):
    lines = open(path).read().split("\n")
    begin = next(i for i, l in enumerate(lines) if "[doc]" in l)
    end = next(i for i, l in enumerate(lines) if "[/doc]" in l)
    body = lines[begin + 1:end]
    indent = min((len(l) - len(l.lstrip()) for l in body if l.strip()), default=0)
    return [l[indent:] for l in body]


def squash(text):
    return " ".join(text.split())


def main():
    root = sys.argv[1]
    update = "--update" in sys.argv
    errors = 0
    checked = 0
    for md in [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True)):
        lines = open(md).read().split("\n")
        out = []
        i = 0
        changed = False
        while i < len(lines):
            line = lines[i]
            fence = re.match(r"^```(\w+)\s*$", line)
            if fence and fence.group(1) in LANGS:
                j = i + 1
                while lines[j] != "```":
                    j += 1
                block = lines[i + 1:j]
                mark = MARK.match(out[-1]) if out else None
                where = f"{os.path.relpath(md, root)}:{i + 1}"
                if not mark:
                    print(f"{where}: a ```{fence.group(1)} block without an example or excerpt marker")
                    errors += 1
                else:
                    kind, path = mark.group(1), os.path.join(root, mark.group(2))
                    checked += 1
                    if kind == "example":
                        want = region(path)
                        if block != want:
                            if update:
                                block = want
                                changed = True
                            else:
                                print(f"{where}: differs from {mark.group(2)} (check_docs.py ROOT --update)")
                                errors += 1
                    elif squash("\n".join(block)).rstrip(";") not in squash(open(path).read()):
                        print(f"{where}: the excerpt does not stand in {mark.group(2)}")
                        errors += 1
                out.append(line)
                out.extend(block)
                out.append("```")
                i = j + 1
                continue
            out.append(line)
            i += 1
        if changed:
            open(md, "w").write("\n".join(out))
    print(f"docs examples: {checked} blocks checked, {errors} problems")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
