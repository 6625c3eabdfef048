#!/usr/bin/env python3
"""The house's one-way dependencies: every project include of a room's files must point at the
room itself or at a room below it (docs/architecture.md). Prints each include that points up or
sideways as FILE:LINE: ROOM -> ROOM and exits 1; exits 0 when the graph is clean.
Usage: scripts/check_layers.py [REPO_ROOT]"""
import os
import re
import sys

# Each room and the rooms it may include, lowest first. A room may always include itself.
LAYERS = {
    "core": [],
    "geometry": ["core"],
    "render": ["core", "geometry"],
    "plot": ["core"],
    "synthetic": ["core", "geometry", "render"],
    "web": ["core"],
    "avatar": ["core", "geometry", "render", "web"],
    "bundle": ["core", "geometry"],
    "models": ["core", "geometry", "bundle"],
    "export": ["core", "geometry", "bundle", "models"],
    "infer": ["core", "geometry", "render", "bundle"],
    "annotate": ["core", "geometry", "web"],
    "data": ["core", "geometry", "render", "bundle"],
    "train": ["core", "geometry", "bundle", "models", "export", "data"],
    "correspond": ["core", "geometry", "render", "bundle", "models", "export", "data", "train", "web", "annotate"],
    "translate": ["core", "geometry", "render", "bundle", "models", "export", "data", "train", "web", "annotate", "correspond"],
    "eval": ["core", "geometry", "render", "bundle", "models", "export", "data", "train", "web", "annotate",
             "correspond", "translate"],
    "pipeline": ["core", "geometry", "bundle", "models", "export", "data", "train", "web", "annotate", "correspond"],
    "cli": ["core", "geometry", "render", "avatar", "synthetic", "bundle", "models", "export", "infer", "web", "annotate", "data",
            "train", "correspond", "translate", "eval", "pipeline", "plot"],
    "bench": ["core", "geometry", "render", "synthetic", "bundle", "models", "export", "infer"],
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/[^"]+"')


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    problems = []
    for room, allowed in LAYERS.items():
        folder = os.path.join(root, room)
        if not os.path.isdir(folder):
            problems.append(f"{room}/: the room is missing")
            continue
        for name in sorted(os.listdir(folder)):
            if not name.endswith((".h", ".cpp")):
                continue
            path = os.path.join(folder, name)
            with open(path, encoding="utf-8") as f:
                for number, line in enumerate(f, 1):
                    m = INCLUDE.match(line)
                    if m and m.group(1) in LAYERS and m.group(1) != room and m.group(1) not in allowed:
                        problems.append(f"{room}/{name}:{number}: {room} -> {m.group(1)} "
                                        f"({room} may include: {', '.join(allowed) or 'nothing of the project'})")
    for p in problems:
        print(p)
    if problems:
        print(f"check_layers: {len(problems)} include(s) against the house's one-way dependencies")
        return 1
    print(f"check_layers: {len(LAYERS)} rooms, every include points down")
    return 0


if __name__ == "__main__":
    sys.exit(main())
