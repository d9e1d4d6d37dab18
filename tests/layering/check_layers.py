#!/usr/bin/env python3
"""Fails when a module includes a header of a module it may not use (docs/architecture.md).

Each module publishes include/lf/<module>/; a file may include lf/<other>/ only for the modules
below it in LAYERS, and the generated wire code (lightfarm/v1/...) only at the edges. The build
refuses most violations already (a library sees only the headers of what it links); this also
catches a header that happens to be visible through another link.
"""
import argparse
import pathlib
import re
import sys
import tempfile

# What each module may include, itself included.
LAYERS = {
    "core": {"core"},
    "kernels": {"core", "kernels"},
    "job": {"core", "job"},
    "local": {"core", "kernels", "job", "local"},
    "proto": {"proto"},
    "wire": {"core", "job", "proto", "wire"},
    "server": {"core", "job", "proto", "wire", "server"},
    "worker": {"core", "kernels", "job", "local", "proto", "wire", "worker"},
    "client": {"core", "kernels", "job", "local", "proto", "wire", "client"},
}
# The generated protobuf code (lightfarm/v1/*.pb.h) belongs to the edges.
WIRE_USERS = {"proto", "wire", "server", "worker", "client"}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def violations(root: pathlib.Path):
    for module, allowed in LAYERS.items():
        for path in sorted((root / module).rglob("*")):
            if path.suffix not in (".h", ".cc") or not path.is_file():
                continue
            text = path.read_text(errors="replace")
            for match in INCLUDE.finditer(text):
                header = match.group(1)
                line = text.count("\n", 0, match.start()) + 1
                where = f"{path.relative_to(root)}:{line}"
                parts = header.split("/")
                if header.startswith("lf/") and len(parts) > 2 and parts[1] in LAYERS:
                    if parts[1] not in allowed:
                        yield f"{where}: {module} includes {header} ({parts[1]} is not below {module})"
                elif header.startswith("lightfarm/v1/") and module not in WIRE_USERS:
                    yield f"{where}: {module} includes generated wire code {header}"
                elif parts[0] in LAYERS and len(parts) > 1:
                    yield f"{where}: {module} includes {header} by a source path; use lf/{parts[0]}/..."


def self_test() -> int:
    """The checker itself must fail on a worker file that includes a server header."""
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        (root / "worker" / "src").mkdir(parents=True)
        (root / "worker" / "src" / "bad.cc").write_text('#include "lf/server/scheduler.h"\n')
        found = list(violations(root))
        if len(found) != 1 or "worker includes lf/server/scheduler.h" not in found[0]:
            print("self-test: the violation was not reported:", found)
            return 1
        print("self-test: reported", found[0])
        return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("root", type=pathlib.Path, help="the repository")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    found = list(violations(args.root))
    for v in found:
        print(v)
    if found:
        print(f"{len(found)} include(s) break the layers (docs/architecture.md)")
        return 1
    print("layers ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
