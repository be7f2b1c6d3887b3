#!/usr/bin/env python3
"""clang-tidy over every translation unit we own, in a build's compile_commands.json.

A unit is linted again unless the same unit was found clean before with the same inputs: its
preprocessed text (every header it includes, as the compiler sees it), its compile command, the
clang-tidy configuration and clang-tidy's version, with the checkout's path taken out so that
clones in other folders share the record. The record of clean units lives outside the checkout
(GEOJCBB_LINT_CACHE, default ~/.cache/geojcbb/lint; "off" lints every unit). A finding is never
recorded, so it shows again on every run until it is fixed.

usage: lint.py BUILD_DIR CONFIG_FILE
"""
import concurrent.futures
import hashlib
import json
import os
import shlex
import subprocess
import sys

TIDY = "clang-tidy-14"


def main() -> int:
    build, config = sys.argv[1], sys.argv[2]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    cache = os.environ.get("GEOJCBB_LINT_CACHE", os.path.expanduser("~/.cache/geojcbb/lint"))
    entries = {}
    for e in json.load(open(os.path.join(build, "compile_commands.json"))):
        f = e["file"]
        if "/build/" not in f and f.endswith(".cpp"):
            entries[f] = e
    version = subprocess.run([TIDY, "--version"], capture_output=True, text=True, check=True).stdout
    salt = (version + open(config).read()).encode()

    def preprocess_key(e):
        args = e["arguments"] if "arguments" in e else shlex.split(e["command"])
        cmd, skip = [], False
        for a in args:
            if skip:
                skip = False
                continue
            if a in ("-o", "-MT", "-MF", "-MQ"):
                skip = True
                continue
            if a in ("-c", "-MD", "-MMD") or a.startswith("-fstack-usage"):
                continue
            cmd.append(a)
        pre = subprocess.run(cmd + ["-E", "-o", "-"], cwd=e["directory"], capture_output=True)
        if pre.returncode != 0:
            return None  # let clang-tidy report it
        h = hashlib.sha256(salt)
        h.update(" ".join(args).replace(root, "@ROOT@").encode())
        h.update(pre.stdout.replace(root.encode(), b"@ROOT@"))
        return h.hexdigest()

    jobs = os.cpu_count() or 1
    files = sorted(entries)
    use_cache = cache != "off"
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        keys = dict(zip(files, pool.map(lambda f: preprocess_key(entries[f]) if use_cache else None, files)))
    todo = [f for f in files if not (keys[f] and os.path.exists(os.path.join(cache, keys[f])))]
    print(f"== lint: {TIDY} --config-file={os.path.relpath(config, root)} on {len(files)} translation units "
          f"({len(files) - len(todo)} unchanged since found clean, {len(todo)} to lint)", flush=True)

    def tidy(f):
        r = subprocess.run([TIDY, "--quiet", f"--config-file={config}", "-p", build,
                            "--extra-arg=-Wno-ignored-optimization-argument", f], capture_output=True, text=True)
        return f, r

    failed = 0
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        for f, r in pool.map(tidy, todo):
            if r.returncode == 0:
                if use_cache and keys[f]:
                    os.makedirs(cache, exist_ok=True)
                    open(os.path.join(cache, keys[f]), "w").write(os.path.relpath(f, root) + "\n")
            else:
                failed += 1
                sys.stdout.write(r.stdout)
                sys.stderr.write(r.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
