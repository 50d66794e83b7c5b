#!/usr/bin/env python3
"""Checks the crate boundaries of STYLE.md ("Boundaries") with `cargo metadata`.

- core depends on no bodyseg crate;
- a stage crate (calib, parsing, project, people, refine, eval, synth, ros2) depends only
  on core, and project, people, synth and ros2 also on calib; calib also on io (its atomic
  writes);
- io depends only on core; testkit only on core;
- only pipeline, the root package (the `bodyseg` binary) and lab (the studies) may depend
  on every crate; no crate depends on lab;
- testkit is never a normal dependency, and synth is one only of pipeline and the binary:
  lower crates may use them as dev-dependencies (tests, benches) only;
- view (the Rerun writer) depends only on core and calib, and io for its `.rrd` file
  (`bodyseg_io::DirectFile`), and it is the only crate that names the Rerun SDK (re_sdk,
  rerun, re_*), optionally (feature `rerun`).

Prints every violation and exits 1 if there is any; exits 0 and prints a one-line summary
otherwise. Standard library only; run from anywhere.
"""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PREFIX = "bodyseg-"
ROOT_PACKAGE = "bodyseg"

# Normal (and build) dependencies each crate may have among bodyseg's crates, by short
# name (without the "bodyseg-" prefix). None = any.
ALLOWED = {
    "core": set(),
    "calib": {"core", "io"},
    "parsing": {"core"},
    "project": {"core", "calib"},
    "people": {"core", "calib"},
    "refine": {"core"},
    "eval": {"core"},
    "synth": {"core", "calib"},
    # ROS 2 bags (bodyseg import ros2): decoding only, no file system; pipeline uses it.
    "ros2": {"core", "calib"},
    "io": {"core"},
    "testkit": {"core"},
    # The Rerun writer: stage types in, `.rrd` out (written through io's DirectFile).
    "view": {"core", "calib", "io"},
    "pipeline": None,
    # Studies (reports, sweeps, timing tools): may use everything, nothing uses them.
    "lab": None,
    ROOT_PACKAGE: None,
}

# Crates no other crate may depend on, in any way (not even from tests).
LEAVES = {"lab"}

# Crates that lower crates may use from tests and benches only.
DEV_ONLY = {"testkit", "synth"}
# The only crate that may name the Rerun SDK, and only as an optional dependency.
RERUN_CRATE = "view"


def is_rerun(name: str) -> bool:
    return name in ("rerun", "re_sdk") or name.startswith("re_")


# Crates that may have synth as a normal dependency (they "see them all").
SEES_ALL = {"pipeline", "lab", ROOT_PACKAGE}


def short(name: str) -> str:
    return name[len(PREFIX):] if name.startswith(PREFIX) else name


def is_ours(name: str) -> bool:
    return name == ROOT_PACKAGE or name.startswith(PREFIX)


def metadata() -> dict:
    try:
        out = subprocess.run(
            ["cargo", "metadata", "--format-version", "1", "--no-deps"],
            cwd=ROOT,
            check=True,
            capture_output=True,
            text=True,
        )
    except (OSError, subprocess.CalledProcessError) as e:
        stderr = getattr(e, "stderr", "") or ""
        sys.exit(f"check_boundaries: cargo metadata failed: {e}\n{stderr}")
    return json.loads(out.stdout)


def violations(meta: dict) -> list[str]:
    found = []
    packages = [p for p in meta["packages"] if is_ours(p["name"])]
    for pkg in sorted(packages, key=lambda p: p["name"]):
        me = short(pkg["name"])
        if me not in ALLOWED:
            found.append(
                f"{pkg['name']}: not in scripts/check_boundaries.py's table; add its allowed "
                "dependencies there (and its line to ARCHITECTURE.md)"
            )
            continue
        allowed = ALLOWED[me]
        for dep in pkg["dependencies"]:
            if is_rerun(dep["name"]):
                if me != RERUN_CRATE or not dep.get("optional", False):
                    found.append(
                        f"{pkg['name']}: depends on {dep['name']}; only {PREFIX}{RERUN_CRATE} "
                        "may, optionally (feature `rerun`): the default build has no Rerun"
                    )
                continue
            if not is_ours(dep["name"]):
                continue
            other = short(dep["name"])
            kind = dep.get("kind") or "normal"
            if other == me:
                continue
            if other in LEAVES:
                found.append(
                    f"{pkg['name']}: {kind} dependency on {dep['name']}, which nothing may "
                    "depend on (study code)"
                )
                continue
            if kind == "dev":
                # Tests and benches may also use the test-scene generators.
                ok = allowed is None or other in allowed or other in DEV_ONLY
                if not ok:
                    found.append(
                        f"{pkg['name']}: dev-dependency on {dep['name']} (allowed: "
                        f"{describe(allowed | DEV_ONLY)})"
                    )
                continue
            if other == "testkit" or (other in DEV_ONLY and me not in SEES_ALL):
                found.append(
                    f"{pkg['name']}: {kind} dependency on {dep['name']}, which may be only a "
                    "dev-dependency here (tests, benches)"
                )
                continue
            if allowed is not None and other not in allowed:
                found.append(
                    f"{pkg['name']}: {kind} dependency on {dep['name']} (allowed: "
                    f"{describe(allowed)}; STYLE.md 'Boundaries')"
                )
    return found


def describe(names: set) -> str:
    return ", ".join(PREFIX + n for n in sorted(names)) or "no bodyseg crate"


def main() -> int:
    meta = metadata()
    found = violations(meta)
    for v in found:
        print(f"boundary violation: {v}")
    checked = sum(1 for p in meta["packages"] if is_ours(p["name"]))
    if found:
        print(f"check_boundaries: {len(found)} violation(s) in {checked} crates")
        return 1
    print(f"check_boundaries: {checked} crates, boundaries respected")
    return 0


if __name__ == "__main__":
    sys.exit(main())
