#!/usr/bin/env python3
"""Checks deploy/ against itself and against the binaries (ctest deploy_manifests).

    check_deploy.py BIN_DIR SOURCE_DIR

- every YAML file under deploy/ parses (all documents);
- every container's command/args (Dockerfile CMD, Compose, Kubernetes) and every systemd
  ExecStart (expanded with its example env file) is run through the binary with --check-config,
  with the files its volumes, Secrets and env files provide made in a temporary folder (the
  certificates are docs/deploy.md's, made by its own openssl commands);
- ports, Secret names and keys, mount paths, volumes, the user and the flags' paths agree across
  the Dockerfile, compose.yaml, the Kubernetes manifests and the systemd units;
- probes and scrapes of --http use HTTPS where the server has a certificate;
- a real server with docs/deploy.md's certificates accepts a worker's client certificate and a
  token, answers Compose's health check, and serves the metric the HPA scales on over HTTPS.

Every failure names the file and the mismatch; all are printed, then the exit status is 1.
"""
import os
import re
import shutil
import ssl
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

import yaml
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'support'))
from processes import stop_all  # noqa: E402  (tests/support)

BIN_DIR, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
DEPLOY = os.path.join(SRC, "deploy")
DOCKERFILE = os.path.join(DEPLOY, "docker", "Dockerfile")
COMPOSE = os.path.join(DEPLOY, "docker", "compose.yaml")
K8S = os.path.join(DEPLOY, "kubernetes")
SYSTEMD = os.path.join(DEPLOY, "systemd")
DOCS = os.path.join(SRC, "docs", "deploy.md")
HPA_METRIC = "lightfarm_queue_depth"
UID = "10001"

# Flags whose value is a path, per binary; the ones that must agree across deployments.
FILE_FLAGS = {"--tls-cert", "--tls-key", "--tls-client-ca", "--tls-ca", "--token-file"}
DIR_FLAGS = {"--data-dir", "--cache-dir"}
SAME_PATH_FLAGS = FILE_FLAGS | {"--data-dir"}
PORT_FLAGS = {"--listen", "--http", "--server"}

errors = []
TMP = tempfile.mkdtemp(prefix="check_deploy.")


def rel(path):
    return os.path.relpath(path, SRC)


def fail(path, message):
    errors.append(f"{rel(path) if os.path.isabs(path) else path}: {message}")


# The module the binaries load to read OpenVDB grids, and where from (lf/core/vdb_reader.h).
VDB_MODULE = "liblf_vdb.so"
VDB_MODULE_DIR = "../lib/lightfarm"


def binary(name):
    return os.path.join(BIN_DIR, name)


def flag_values(args):
    """{flag: value} of --flag=value and --flag value arguments."""
    values, i = {}, 0
    while i < len(args):
        a = args[i]
        if a.startswith("--") and "=" in a:
            k, v = a.split("=", 1)
            values[k] = v
        elif a.startswith("--") and i + 1 < len(args) and not args[i + 1].startswith("--"):
            values[a] = args[i + 1]
            i += 1
        elif a.startswith("--"):
            values[a] = ""
        i += 1
    return values


def port_of(hostport):
    m = re.fullmatch(r"(.*):(\d+)", hostport or "")
    return int(m.group(2)) if m else None


def server_ports(v):
    """The ports a server's flags listen on: --listen, --http and --grpc-health."""
    return {port_of(v[f]) for f in ("--listen", "--http", "--grpc-health") if v.get(f)}


def host_of(hostport):
    m = re.fullmatch(r"(.*):(\d+)", hostport or "")
    return m.group(1) if m else None


# ---------------------------------------------------------------- certificates (docs/deploy.md)

def make_pki():
    """Runs docs/deploy.md's certificate block; returns {name: path} of its files."""
    text = open(DOCS).read()
    m = re.search(r"<!-- check_deploy: pki[^>]*-->\s*```sh\n(.*?)```", text, re.S)
    if not m:
        fail(DOCS, "no ```sh block after <!-- check_deploy: pki --> (the certificate commands)")
        return None
    work = os.path.join(TMP, "docs")
    os.makedirs(work)
    r = subprocess.run(["bash", "-euo", "pipefail", "-c", m.group(1)], cwd=work,
                       capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        fail(DOCS, f"the certificate commands failed ({r.returncode}): {r.stderr.strip()[-800:]}")
        return None
    pki = {n: os.path.join(work, "pki", n)
           for n in ("ca.crt", "server.crt", "server.key", "worker.crt", "worker.key")}
    for n, p in pki.items():
        if not os.path.isfile(p):
            fail(DOCS, f"the certificate commands made no pki/{n}")
            return None
    return pki


def san_names(cert):
    r = subprocess.run(["openssl", "x509", "-in", cert, "-noout", "-ext", "subjectAltName"],
                       capture_output=True, text=True)
    return set(re.findall(r"(?:DNS|IP Address):([^,\s]+)", r.stdout))


# ---------------------------------------------------------------- running --check-config

def content_for(name, role, pki):
    """What a provided file holds, by its name: a key, the CA, a certificate or a token."""
    base = os.path.basename(name)
    if "token" in base:
        return "lf-check-deploy-token\n"
    if base.endswith(".key"):
        return open(pki[f"{role}.key"]).read()
    if base.startswith("ca") or "-ca" in base or "_ca" in base:
        return open(pki["ca.crt"]).read()
    if base.endswith((".crt", ".pem")):
        return open(pki[f"{role}.crt"]).read()
    return "placeholder\n"


def check_config(where, exe, args, files, dirs, pki, env=None):
    """Runs EXE ARGS --check-config in a fresh root where FILES (absolute paths) and DIRS
    exist; every absolute path in ARGS is moved under that root."""
    if pki is None:
        return
    role = "server" if exe.endswith("server") else "worker"
    root = tempfile.mkdtemp(prefix="root.", dir=TMP)
    for d in dirs:
        os.makedirs(root + d, exist_ok=True)
    for f in files:
        os.makedirs(os.path.dirname(root + f), exist_ok=True)
        with open(root + f, "w") as out:
            out.write(content_for(f, role, pki))
    values = flag_values(args)
    for flag in FILE_FLAGS:
        if flag in values and values[flag] not in files:
            fail(where, f"{flag}={values[flag]}: no volume, Secret or env file provides it "
                        f"(provided: {', '.join(sorted(files)) or 'nothing'})")
    for flag in DIR_FLAGS:
        if flag in values and not any(values[flag] == d or values[flag].startswith(d + "/")
                                      for d in dirs):
            fail(where, f"{flag}={values[flag]}: not on a volume (volumes: "
                        f"{', '.join(sorted(dirs)) or 'none'})")

    def moved(a):
        if a.startswith("--") and "=" in a:
            k, v = a.split("=", 1)
            return f"{k}={root + v}" if v.startswith("/") else a
        return root + a if a.startswith("/") else a

    run_args = [moved(a) for a in args] + ["--check-config"]
    os.makedirs(os.path.join(root, "tmp"), exist_ok=True)
    r = subprocess.run([binary(exe)] + run_args, capture_output=True, text=True, timeout=60,
                       env=dict(os.environ, **(env or {})))
    if r.returncode != 0 or "config ok" not in r.stdout:
        why = " ".join((r.stderr.strip() or r.stdout.strip()).replace(root, "").split())
        fail(where, f"{exe} --check-config exits {r.returncode}: {why[-600:]} "
                    f"(arguments: {' '.join(args)})")


# ---------------------------------------------------------------- YAML

def check_yaml_parses():
    docs = {}
    for dirpath, _, names in os.walk(DEPLOY):
        for n in sorted(names):
            if n.endswith((".yaml", ".yml")):
                p = os.path.join(dirpath, n)
                try:
                    docs[p] = [d for d in yaml.safe_load_all(open(p)) if d is not None]
                except yaml.YAMLError as e:
                    fail(p, f"does not parse: {e}")
    if not docs:
        fail(DEPLOY, "no YAML files")
    return docs


# ---------------------------------------------------------------- Dockerfile

def parse_dockerfile():
    """{stage: {"from", "expose", "user", "volume", "entrypoint", "cmd", "run", "copy"}}."""
    text = re.sub(r"\\\n", " ", open(DOCKERFILE).read())
    stages, stage = {}, None
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        word, _, rest = line.partition(" ")
        word = word.upper()
        if word == "FROM":
            m = re.match(r"(\S+)(?:\s+AS\s+(\S+))?", rest, re.I)
            stage = {"from": m.group(1), "expose": set(), "user": None, "volume": [],
                     "entrypoint": None, "cmd": None, "run": [], "copy": []}
            stages[m.group(2) or f"#{len(stages)}"] = stage
        elif stage is None:
            continue
        elif word == "EXPOSE":
            stage["expose"] |= {int(p.split("/")[0]) for p in rest.split()}
        elif word == "USER":
            stage["user"] = rest.strip()
        elif word == "VOLUME":
            stage["volume"] += yaml.safe_load(rest) if rest.startswith("[") else rest.split()
        elif word in ("ENTRYPOINT", "CMD"):
            try:
                stage[word.lower()] = yaml.safe_load(rest)  # JSON form
            except yaml.YAMLError:
                stage[word.lower()] = None
            if not isinstance(stage[word.lower()], list):
                fail(DOCKERFILE, f"{word} {rest}: use the JSON (exec) form")
        elif word == "RUN":
            stage["run"].append(rest)
        elif word == "COPY":
            stage["copy"].append(rest)
    # A stage inherits its base stage's user.
    for s in stages.values():
        if s["user"] is None and s["from"] in stages:
            s["user"] = stages[s["from"]]["user"]
    return stages


def installed_packages(stage, stages):
    pkgs = set()
    while stage:
        for run in stage["run"]:
            for m in re.finditer(r"apt-get install ([^&;]*)", run):
                pkgs |= {w for w in m.group(1).split() if not w.startswith("-")}
        stage = stages.get(stage["from"])
    return pkgs


# Packages every debian:12-slim has (apt and dpkg need them).
BASE_PACKAGES = {"libc6", "libgcc-s1", "libstdc++6", "zlib1g"}


def linked_packages(exe):
    """The Debian packages of the shared libraries EXE links, or None where dpkg is missing."""
    if not shutil.which("dpkg") or not shutil.which("ldd"):
        return None
    r = subprocess.run(["ldd", binary(exe)], capture_output=True, text=True)
    libs = {lib: [lib, "/usr" + lib, os.path.realpath(lib), "/usr" + os.path.realpath(lib)]
            for lib in re.findall(r"=> (/\S+)", r.stdout)}
    # One dpkg -S for all (it is slow): "package:arch: path" per path it knows.
    q = subprocess.run(["dpkg", "-S"] + sorted({c for cs in libs.values() for c in cs}),
                       capture_output=True, text=True)
    owner = {}
    for line in q.stdout.splitlines():
        pkg, _, path = line.partition(": ")
        owner[path.strip()] = pkg.split(":")[0]
    pkgs = set()
    for lib, candidates in libs.items():
        found = next((owner[c] for c in candidates if c in owner), None)
        if found is None:
            return None  # a library of no package (a local build): cannot say
        pkgs.add(found)
    return pkgs


def check_dockerfile(stages, pki):
    images = {}
    build = next((s for s in stages.values() if any("deploy/build.sh" in r for r in s["run"])),
                 None)
    if build is None:
        fail(DOCKERFILE, "no stage runs deploy/build.sh")
    elif not any("deploy/install-deps.sh" in r for r in build["run"]):
        fail(DOCKERFILE, "the build stage does not run deploy/install-deps.sh")
    for name, s in stages.items():
        if not s["from"].startswith(("debian:12", "debian:bookworm")) and s["from"] not in stages:
            fail(DOCKERFILE, f"stage {name} is FROM {s['from']}, not debian:12 (bookworm)")
    if not any(re.search(rf"useradd\b.*--uid {UID}\b.*\blightfarm\b", r)
               for s in stages.values() for r in s["run"]):
        fail(DOCKERFILE, f"no `useradd --uid {UID} ... lightfarm`")
    for target, exe in (("server", "lightfarm-server"), ("worker", "lightfarm-worker")):
        s = stages.get(target)
        if s is None:
            fail(DOCKERFILE, f"no stage (target) {target}")
            continue
        entry = s["entrypoint"] or []
        if not entry or os.path.basename(entry[0]) != exe:
            fail(DOCKERFILE, f"target {target}: ENTRYPOINT {entry} is not {exe}")
            continue
        if not any(re.search(rf"--from=\S+\s+\S*/{exe}\s+{re.escape(entry[0])}$", c)
                   for c in s["copy"]):
            fail(DOCKERFILE, f"target {target}: no COPY --from=... {exe} {entry[0]}")
        if (s["user"] or "").split(":")[0] not in (UID, "lightfarm"):
            fail(DOCKERFILE, f"target {target}: USER {s['user']}, not {UID} (lightfarm)")
        # The OpenVDB module goes where the binary looks for it (lf/core/vdb_reader.h):
        # ../lib/lightfarm from the binary's directory.
        module_path = os.path.normpath(os.path.join(os.path.dirname(entry[0]), VDB_MODULE_DIR,
                                                    VDB_MODULE))
        if not any(re.search(rf"--from=\S+\s+\S*/{re.escape(VDB_MODULE)}\s+"
                             rf"{re.escape(module_path)}$", c)
                   for c in s["copy"]):
            fail(DOCKERFILE, f"target {target}: no COPY --from=... {VDB_MODULE} {module_path} "
                             f"(reading OpenVDB grids needs it)")
        other = [c for c in s["copy"]
                 if "--from" in c and f"/{exe}" not in c and f"/{VDB_MODULE}" not in c]
        if other:
            fail(DOCKERFILE, f"target {target}: copies more than its binary and "
                             f"{VDB_MODULE}: {other}")
        for program in (exe, VDB_MODULE):
            linked = linked_packages(program)
            if linked is None:
                continue
            missing = linked - BASE_PACKAGES - installed_packages(s, stages)
            if missing:
                fail(DOCKERFILE, f"target {target}: {program} links libraries of "
                                 f"{', '.join(sorted(missing))}, which it does not install")
        images[target] = {"exe": exe, "entry": entry, "cmd": s["cmd"] or [],
                          "expose": s["expose"], "volume": s["volume"]}
    server, worker = images.get("server"), images.get("worker")
    if server:
        args = server["cmd"]
        v = flag_values(args)
        if server["expose"] != server_ports(v):
            fail(DOCKERFILE, f"target server: EXPOSE {sorted(server['expose'])} is not the "
                             f"ports of CMD's --listen, --http and --grpc-health")
        if server["volume"] != [v.get("--data-dir")]:
            fail(DOCKERFILE, f"target server: VOLUME {server['volume']} is not CMD's "
                             f"--data-dir {v.get('--data-dir')}")
        check_config(f"{rel(DOCKERFILE)} (target server CMD)", "lightfarm-server", args,
                     {v[f] for f in FILE_FLAGS if f in v}, set(server["volume"]), pki)
    if worker:
        v = flag_values(worker["cmd"])
        if worker["expose"]:
            fail(DOCKERFILE, f"target worker: EXPOSE {sorted(worker['expose'])}, but a worker "
                             f"listens on no port")
        check_config(DOCKERFILE + " (target worker CMD)", "lightfarm-worker", worker["cmd"],
                     {v[f] for f in FILE_FLAGS if f in v},
                     {v["--cache-dir"]} if "--cache-dir" in v else set(), pki)
    return images


# ---------------------------------------------------------------- Compose

def interpolate(value):
    """Compose's ${VAR:-default}, from the default (the environment is ignored)."""
    def one(m):
        if m.group(2) is None:
            fail(COMPOSE, f"${{{m.group(1)}}} has no default")
            return ""
        return m.group(3)
    return re.sub(r"\$\{(\w+)(:?-(.*?))?\}", one, value)


# Files a bind-mounted ./secrets folder holds (docs/deploy.md's layout).
SECRETS_FOLDER_FILES = ("tls.crt", "tls.key", "ca.crt")


def check_compose(docs, images, pki):
    if COMPOSE not in docs or not docs[COMPOSE]:
        fail(COMPOSE, "missing, empty or unparsable")
        return {}
    compose = docs[COMPOSE][0]
    services = compose.get("services", {})
    named_volumes = set((compose.get("volumes") or {}).keys())
    found = {}
    for name, svc in services.items():
        where = f"{rel(COMPOSE)} (service {name})"
        target = (svc.get("build") or {}).get("target")
        if target not in images:
            errors.append(f"{where}: build target {target} is not a Dockerfile target")
            continue
        dockerfile = (svc.get("build") or {}).get("dockerfile")
        context = os.path.normpath(os.path.join(os.path.dirname(COMPOSE),
                                                (svc.get("build") or {}).get("context", ".")))
        if dockerfile and os.path.normpath(os.path.join(context, dockerfile)) != DOCKERFILE:
            errors.append(f"{where}: build {context}/{dockerfile} is not {rel(DOCKERFILE)}")
        image = images[target]
        args = [interpolate(str(a)) for a in (svc.get("command") or image["cmd"])]
        v = flag_values(args)
        files, dirs, named_dirs = set(), set(), set()
        for vol in svc.get("volumes") or []:
            if isinstance(vol, dict):
                source, dest = vol.get("source", ""), vol.get("target", "")
            else:
                parts = vol.split(":")
                source, dest = parts[0], parts[1]
            if source.startswith((".", "/")):
                if not source.startswith("./secrets/"):
                    errors.append(f"{where}: bind mount {source} is not under ./secrets")
                if source.endswith(".token") or os.path.splitext(source)[1]:
                    files.add(dest)
                else:
                    files |= {f"{dest}/{f}" for f in SECRETS_FOLDER_FILES}
            else:
                if source not in named_volumes:
                    errors.append(f"{where}: volume {source} is not declared under volumes:")
                dirs.add(dest)
                named_dirs.add(dest)
        dirs |= set(image["volume"])  # the image's VOLUME: an anonymous volume at worst
        if image["exe"] == "lightfarm-server" and v.get("--data-dir") not in named_dirs:
            errors.append(f"{where}: --data-dir {v.get('--data-dir')} is not on a named volume")
        if image["exe"] == "lightfarm-worker" and "--cache-dir" in v:
            dirs.add(v["--cache-dir"])  # made in the image, owned by the user
        check_config(where, image["exe"], args, files, dirs, pki)
        # Ports: published container ports are the image's EXPOSE and the flags' ports.
        for p in svc.get("ports") or []:
            container = int(str(p.get("target") if isinstance(p, dict) else p).split(":")[-1]
                            .split("/")[0])
            if container not in image["expose"]:
                errors.append(f"{where}: publishes container port {container}, which the "
                              f"Dockerfile target {target} does not EXPOSE "
                              f"{sorted(image['expose'])}")
        if image["exe"] == "lightfarm-server":
            listen = server_ports(v)
            if listen != image["expose"]:
                errors.append(f"{where}: --listen/--http/--grpc-health ports "
                              f"{sorted(listen, key=str)} are not the Dockerfile's EXPOSE "
                              f"{sorted(image['expose'])}")
            test = (svc.get("healthcheck") or {}).get("test")
            if not test:
                errors.append(f"{where}: no healthcheck")
            else:
                script = " ".join(test[1:]) if test[0] in ("CMD", "CMD-SHELL") else str(test)
                ports = {int(x) for x in re.findall(r"127\.0\.0\.1[/:](\d+)", script)}
                if ports != {port_of(v.get("--http"))}:
                    errors.append(f"{where}: healthcheck asks port(s) {sorted(ports)}, not "
                                  f"--http's {port_of(v.get('--http'))}")
                found["healthcheck"] = test
        if image["exe"] == "lightfarm-worker":
            host = host_of(v.get("--server"))
            server = services.get(host)
            if server is None:
                errors.append(f"{where}: --server {v.get('--server')}: no service {host}")
            else:
                sv = flag_values([interpolate(str(a)) for a in server.get("command") or []])
                if port_of(v.get("--server")) != port_of(sv.get("--listen")):
                    errors.append(f"{where}: --server port {port_of(v.get('--server'))} is not "
                                  f"{host}'s --listen port {port_of(sv.get('--listen'))}")
            if host not in (svc.get("depends_on") or {}):
                errors.append(f"{where}: does not depend_on {host}")
            if not (svc.get("deploy") or {}).get("replicas"):
                errors.append(f"{where}: no deploy.replicas")
        found[image["exe"]] = (where, args)
    return found


# ---------------------------------------------------------------- Kubernetes

def k8s_objects(docs):
    kust_path = os.path.join(K8S, "kustomization.yaml")
    kust = (docs.get(kust_path) or [{}])[0]
    resources = kust.get("resources") or []
    objects = []
    for r in resources:
        p = os.path.join(K8S, r)
        if p not in docs:
            fail(kust_path, f"resource {r} does not exist (or is not YAML)")
            continue
        objects += [(p, o) for o in docs[p]]
    for p in docs:
        if os.path.dirname(p) == K8S and p != kust_path and os.path.relpath(p, K8S) not in \
                resources and not p.endswith("-values.yaml"):
            fail(kust_path, f"does not list {os.path.relpath(p, K8S)}")
    if shutil.which("kubectl"):
        r = subprocess.run(["kubectl", "kustomize", K8S], capture_output=True, text=True,
                           timeout=60)
        if r.returncode != 0:
            fail(kust_path, f"kubectl kustomize fails: {r.stderr.strip()[-600:]}")
    return objects


def quantity(q):
    q = str(q)
    return int(-(-int(q[:-1]) // 1000)) if q.endswith("m") else int(-(-float(q) // 1))


def expand_k8s(arg, container, where):
    """$(VAR) from the container's env (value, or resourceFieldRef of its own resources)."""
    env = {e["name"]: e for e in container.get("env") or []}

    def one(m):
        e = env.get(m.group(1))
        if e is None:
            errors.append(f"{where}: {arg} uses $({m.group(1)}), which env does not set")
            return ""
        if "value" in e:
            return str(e["value"])
        ref = (e.get("valueFrom") or {}).get("resourceFieldRef")
        if ref:
            kind, res = ref["resource"].split(".")
            value = ((container.get("resources") or {}).get(kind) or {}).get(res)
            if value is None:
                errors.append(f"{where}: $({m.group(1)}) reads {ref['resource']}, which the "
                              f"container does not set")
                return ""
            return str(quantity(value))
        return "from-field"
    return re.sub(r"\$\((\w+)\)", one, arg)


def check_kubernetes(docs, images, pki):
    objects = k8s_objects(docs)
    by_kind = {}
    for p, o in objects:
        by_kind.setdefault(o.get("kind"), []).append((p, o))
    secrets = {o["metadata"]["name"]: (p, o) for p, o in by_kind.get("Secret", [])}
    for name, (p, o) in secrets.items():
        keys = set((o.get("stringData") or {}).keys()) | set((o.get("data") or {}).keys())
        if o.get("type") == "kubernetes.io/tls" and not {"tls.crt", "tls.key"} <= keys:
            fail(p, f"Secret {name} is kubernetes.io/tls without tls.crt and tls.key")
        if o.get("data"):
            fail(p, f"Secret {name} has data: the repository holds placeholders only")
        for k, v in (o.get("stringData") or {}).items():
            if not str(v).startswith("REPLACE-ME"):
                fail(p, f"Secret {name} key {k} is not a REPLACE-ME placeholder")
    found = {}
    services = by_kind.get("Service", [])
    workloads = by_kind.get("StatefulSet", []) + by_kind.get("Deployment", [])
    for p, w in workloads:
        spec, name = w["spec"], w["metadata"]["name"]
        pod = spec["template"]["spec"]
        labels = spec["template"]["metadata"].get("labels") or {}
        selector = spec["selector"].get("matchLabels") or {}
        if any(labels.get(k) != v for k, v in selector.items()):
            fail(p, f"{w['kind']} {name}: selector {selector} does not match its pod labels")
        if str((pod.get("securityContext") or {}).get("runAsUser")) != UID:
            fail(p, f"{w['kind']} {name}: runAsUser is not {UID} (the images' user)")
        volumes = {v["name"]: v for v in pod.get("volumes") or []}
        claims = {c["metadata"]["name"] for c in spec.get("volumeClaimTemplates") or []}
        for c in pod["containers"]:
            where = f"{rel(p)} ({w['kind']} {name}, container {c['name']})"
            image = next((i for i in images.values()
                          if c.get("image", "").split("/")[-1].split(":")[0] == i["exe"]), None)
            if image is None:
                errors.append(f"{where}: image {c.get('image')} is none of the Dockerfile's")
                continue
            if c.get("command"):
                errors.append(f"{where}: sets command: the image's ENTRYPOINT is the binary")
            args = [expand_k8s(str(a), c, where) for a in c.get("args") or image["cmd"]]
            v = flag_values(args)
            files, dirs = set(), set()
            for m in c.get("volumeMounts") or []:
                mp = m["mountPath"]
                if m["name"] in claims:
                    dirs.add(mp)
                    continue
                vol = volumes.get(m["name"])
                if vol is None:
                    errors.append(f"{where}: mounts volume {m['name']}, which the pod lacks")
                    continue
                sources = []
                if "secret" in vol:
                    sources = [(vol["secret"]["secretName"], vol["secret"].get("items"))]
                elif "projected" in vol:
                    sources = [(s["secret"]["name"], s["secret"].get("items"))
                               for s in vol["projected"]["sources"] if "secret" in s]
                else:
                    dirs.add(mp)
                for secret, items in sources:
                    if secret not in secrets:
                        errors.append(f"{where}: mounts Secret {secret}, which "
                                      f"kustomization.yaml does not define")
                        continue
                    sp, so = secrets[secret]
                    keys = set((so.get("stringData") or {}).keys()) | set(
                        (so.get("data") or {}).keys())
                    for it in items or [{"key": k, "path": k} for k in keys]:
                        if it["key"] not in keys:
                            errors.append(f"{where}: Secret {secret} has no key {it['key']} "
                                          f"({rel(sp)} has {sorted(keys)})")
                        path = f"{mp}/{it['path']}"
                        if m.get("subPath"):
                            if it["path"] == m["subPath"]:
                                files.add(mp)
                        else:
                            files.add(path)
            if image["exe"] == "lightfarm-server" and v.get("--data-dir") not in {
                    m["mountPath"] for m in c.get("volumeMounts") or [] if m["name"] in claims}:
                errors.append(f"{where}: --data-dir {v.get('--data-dir')} is not the mount of a "
                              f"volumeClaimTemplate ({sorted(claims)})")
            check_config(where, image["exe"], args, files, dirs, pki)
            ports = {pp["containerPort"]: pp.get("name") for pp in c.get("ports") or []}
            if set(ports) != image["expose"]:
                errors.append(f"{where}: containerPorts {sorted(ports)} are not the Dockerfile's "
                              f"EXPOSE {sorted(image['expose'])}")
            named = {n: port for port, n in ports.items() if n}

            def resolve(port):
                return named.get(port) if isinstance(port, str) else port

            if image["exe"] == "lightfarm-server":
                grpc_port, http_port = port_of(v.get("--listen")), port_of(v.get("--http"))
                health_port = port_of(v.get("--grpc-health")) if v.get("--grpc-health") else None
                if server_ports(v) != set(ports):
                    errors.append(f"{where}: --listen/--http/--grpc-health ports {grpc_port}, "
                                  f"{http_port}, {health_port} are not the containerPorts "
                                  f"{sorted(ports)}")
                probes = {k: c.get(k) for k in ("readinessProbe", "livenessProbe")}
                for kind, probe in probes.items():
                    if not probe:
                        errors.append(f"{where}: no {kind}")
                for kind in ("readinessProbe", "livenessProbe", "startupProbe"):
                    probe = c.get(kind) or {}
                    probed = probe.get("grpc", {}).get("port")
                    if "grpc" in probe and probed not in (grpc_port, health_port):
                        errors.append(f"{where}: {kind} grpc port {probed} is neither "
                                      f"--listen's {grpc_port} nor --grpc-health's {health_port}")
                    if "grpc" in probe and probed == grpc_port and v.get("--tls-cert"):
                        errors.append(f"{where}: {kind} is a grpc probe, which speaks "
                                      f"plaintext, on the TLS port {grpc_port}")
                    if "httpGet" in probe:
                        hg = probe["httpGet"]
                        if resolve(hg.get("port")) != http_port or hg.get("path") != "/healthz":
                            errors.append(f"{where}: {kind} asks {hg.get('path')} on "
                                          f"{hg.get('port')}, not /healthz on --http's "
                                          f"{http_port}")
                        # --http speaks HTTPS when the server has a certificate.
                        scheme = "HTTPS" if v.get("--tls-cert") else "HTTP"
                        if hg.get("scheme", "HTTP") != scheme:
                            errors.append(f"{where}: {kind} asks with scheme "
                                          f"{hg.get('scheme', 'HTTP')}, not {scheme}")
                    if "tcpSocket" in probe and resolve(probe["tcpSocket"].get("port")) not in ports:
                        errors.append(f"{where}: {kind} tcpSocket port "
                                      f"{probe['tcpSocket'].get('port')} is no containerPort")
                matching = [(sp, s) for sp, s in services
                            if all(labels.get(k) == val
                                   for k, val in (s["spec"].get("selector") or {}).items())]
                if not matching:
                    errors.append(f"{where}: no Service selects the pod")
                for sp, s in matching:
                    for sport in s["spec"]["ports"]:
                        target = resolve(sport.get("targetPort", sport["port"]))
                        if target not in ports or sport["port"] != target:
                            errors.append(f"{rel(sp)}: Service {s['metadata']['name']} port "
                                          f"{sport['port']} -> {sport.get('targetPort')} is not "
                                          f"a containerPort of the same number {sorted(ports)}")
                if w["kind"] == "StatefulSet" and spec.get("serviceName") not in {
                        s["metadata"]["name"] for _, s in matching}:
                    fail(p, f"StatefulSet {name}: serviceName {spec.get('serviceName')} is not "
                            f"its Service")
                annotations = spec["template"]["metadata"].get("annotations") or {}
                if annotations.get("prometheus.io/scheme", "http") != (
                        "https" if v.get("--tls-cert") else "http"):
                    fail(p, f"StatefulSet {name}: prometheus.io/scheme "
                            f"{annotations.get('prometheus.io/scheme')} is not --http's")
                if str(annotations.get("prometheus.io/port")) != str(http_port):
                    fail(p, f"StatefulSet {name}: prometheus.io/port "
                            f"{annotations.get('prometheus.io/port')} is not --http's {http_port}")
                found["server-service-names"] = {s["metadata"]["name"] for _, s in matching}
                found["server-ports"] = {grpc_port, http_port}
            found[image["exe"]] = (where, args)
    # Workers reach the server by its Service, on its gRPC port.
    if "lightfarm-worker" in found and "server-service-names" in found:
        where, args = found["lightfarm-worker"]
        server = flag_values(args).get("--server")
        if host_of(server).split(".")[0] not in found["server-service-names"]:
            errors.append(f"{where}: --server {server} is not the server's Service "
                          f"{sorted(found['server-service-names'])}")
        grpc_port = port_of(flag_values(found["lightfarm-server"][1]).get("--listen"))
        if port_of(server) != grpc_port:
            errors.append(f"{where}: --server port {port_of(server)} is not the server's "
                          f"--listen port {grpc_port}")
    # The HPA: the worker Deployment, on the queue metric the adapter serves.
    hpas = by_kind.get("HorizontalPodAutoscaler", [])
    if not hpas:
        fail(K8S, "no HorizontalPodAutoscaler")
    deployments = {o["metadata"]["name"] for _, o in by_kind.get("Deployment", [])}
    values_path = os.path.join(K8S, "prometheus-adapter-values.yaml")
    values = (docs.get(values_path) or [{}])[0]
    for p, h in hpas:
        if h.get("apiVersion") != "autoscaling/v2":
            fail(p, f"HPA apiVersion {h.get('apiVersion')}, not autoscaling/v2")
        ref = h["spec"]["scaleTargetRef"]
        if ref.get("kind") != "Deployment" or ref.get("name") not in deployments:
            fail(p, f"HPA scales {ref.get('kind')} {ref.get('name')}, not a Deployment here")
        for m in h["spec"].get("metrics") or []:
            kind = m.get("type")
            metric = (m.get(kind.lower()) or {}).get("metric", {}).get("name")
            if metric != HPA_METRIC:
                fail(p, f"HPA metric {metric}, not {HPA_METRIC}")
            rules = (values.get("rules") or {}).get("external" if kind == "External" else "custom")
            if not any(r.get("name", {}).get("as") == metric or
                       (metric or "-") in r.get("seriesQuery", "") for r in rules or []):
                fail(values_path, f"no rules.{'external' if kind == 'External' else 'custom'} "
                                  f"rule serves the HPA's {kind} metric {metric}")
    return found


# ---------------------------------------------------------------- systemd

def parse_unit(path):
    entries, section = [], None
    for line in open(path):
        line = line.strip()
        if not line or line.startswith(("#", ";")):
            continue
        if line.startswith("["):
            section = line.strip("[]")
            continue
        k, _, v = line.partition("=")
        entries.append((section, k.strip(), v.strip()))
    return entries


def parse_env(path):
    env = {}
    for line in open(path):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        k, _, v = line.partition("=")
        v = v.strip()
        if len(v) >= 2 and v[0] == v[-1] and v[0] in "'\"":
            v = v[1:-1]
        env[k.strip()] = v
    return env


def expand_exec(path, command, env, instance):
    """systemd's ExecStart: %i, then ${VAR} inside a word and $VAR as words split on spaces."""
    command = command.replace("%i", instance).replace("%%", "%")
    words = []
    for word in command.split():
        m = re.fullmatch(r"\$(\w+)", word)
        if m:
            if m.group(1) not in env:
                fail(path, f"ExecStart uses ${m.group(1)}, which its env file does not set")
            words += env.get(m.group(1), "").split()
            continue

        def var(mm):
            if mm.group(1) not in env:
                fail(path, f"ExecStart uses ${{{mm.group(1)}}}, which its env file does not set")
            return env.get(mm.group(1), "")
        words.append(re.sub(r"\$\{(\w+)\}", var, word))
    return words


def check_systemd(pki):
    found = {}
    instance = "render-01"
    units = [("lightfarm-server.service", "lightfarm-server"),
             ("lightfarm-worker@.service", "lightfarm-worker")]
    sysusers = os.path.join(SYSTEMD, "lightfarm.sysusers.conf")
    for unit, exe in units:
        path = os.path.join(SYSTEMD, unit)
        if not os.path.isfile(path):
            fail(path, "missing")
            continue
        entries = parse_unit(path)
        service = {}
        for section, k, v in entries:
            if section == "Service":
                service.setdefault(k, []).append(v)
        get = lambda k: (service.get(k) or [None])[-1]  # noqa: E731
        env = {}
        for ef in service.get("EnvironmentFile", []):
            optional = ef.startswith("-")
            ef = ef.lstrip("-")
            if not re.fullmatch(r"/etc/lightfarm/[\w%.-]+\.env", ef):
                fail(path, f"EnvironmentFile={ef} is not /etc/lightfarm/*.env")
            local = os.path.join(SYSTEMD, os.path.basename(ef))
            if os.path.isfile(local):
                env.update(parse_env(local))
            elif not optional:
                fail(path, f"EnvironmentFile={ef}: no example {rel(local)}")
        if not service.get("EnvironmentFile"):
            fail(path, "no EnvironmentFile=")
        for k, want in (("NoNewPrivileges", "yes"), ("ProtectSystem", "strict"),
                        ("Restart", "on-failure"), ("PrivateTmp", "yes"),
                        ("ProtectHome", "yes")):
            if get(k) != want:
                fail(path, f"{k}={get(k)}, not {want}")
        if get("DynamicUser") != "yes":
            if get("User") != "lightfarm":
                fail(path, f"User={get('User')}: neither DynamicUser=yes nor User=lightfarm")
            elif not os.path.isfile(sysusers) or not re.search(
                    rf"^u\s+lightfarm\s+{UID}\b", open(sysusers).read(), re.M):
                fail(sysusers, f"does not make the user lightfarm with uid {UID}")
        if get("StateDirectory") != "lightfarm" and exe == "lightfarm-server":
            fail(path, f"StateDirectory={get('StateDirectory')}, not lightfarm")
        words = expand_exec(path, get("ExecStart") or "", env, instance)
        if not words or os.path.basename(words[0]) != exe:
            fail(path, f"ExecStart runs {words[:1]}, not {exe}")
            continue
        args = words[1:]
        v = flag_values(args)
        dirs = set()
        if get("StateDirectory"):
            dirs.add("/var/lib/" + get("StateDirectory").replace("%i", instance))
        if get("CacheDirectory"):
            dirs.add("/var/cache/" + get("CacheDirectory").replace("%i", instance))
        if exe == "lightfarm-server" and v.get("--data-dir") != "/var/lib/lightfarm":
            fail(path, f"--data-dir {v.get('--data-dir')} is not StateDirectory's "
                       f"/var/lib/lightfarm")
        if exe == "lightfarm-worker":
            if v.get("--cache-dir") not in dirs:
                fail(path, f"--cache-dir {v.get('--cache-dir')} is not CacheDirectory's "
                           f"{sorted(dirs)}")
            if v.get("--name") != instance:
                fail(path, f"--name {v.get('--name')} is not the instance (%i)")
        files = {val for val in env.values() if val.startswith("/etc/lightfarm/")}
        check_config(f"{rel(path)} (ExecStart with {', '.join(sorted(os.path.basename(e.lstrip('-')) for e in service.get('EnvironmentFile', [])))})",
                     exe, args, files, dirs, pki)
        found[exe] = (rel(path), args)
        found[exe + "-unit"] = (path, unit)
    # systemd's own check, with the binaries of this build.
    if shutil.which("systemd-analyze") and "lightfarm-server-unit" in found:
        units_dir = os.path.join(TMP, "units")
        os.makedirs(units_dir)
        names = []
        for exe in ("lightfarm-server", "lightfarm-worker"):
            if exe + "-unit" not in found:
                continue
            src, unit = found[exe + "-unit"]
            name = unit.replace("@.", f"@{instance}.")
            with open(os.path.join(units_dir, name), "w") as out:
                out.write(open(src).read().replace("/usr/local/bin/", BIN_DIR.rstrip("/") + "/"))
            names.append(os.path.join(units_dir, name))
        r = subprocess.run(["systemd-analyze", "verify"] + names, capture_output=True, text=True,
                           timeout=60)
        if r.returncode != 0:
            fail(SYSTEMD, f"systemd-analyze verify: {r.stderr.strip()[-800:]}")
    return found


# ---------------------------------------------------------------- across deployments

def check_agreement(deployments):
    """The same paths and ports for the same flags everywhere."""
    for exe in ("lightfarm-server", "lightfarm-worker"):
        seen = {}
        for label, found in deployments.items():
            if exe not in found:
                continue
            where, args = found[exe]
            for flag, value in flag_values(args).items():
                if flag in SAME_PATH_FLAGS or (flag == "--cache-dir" and label != "systemd"):
                    key = flag
                elif flag in PORT_FLAGS:
                    key, value = flag + " port", port_of(value)
                else:
                    continue
                if key in seen and seen[key][1] != value:
                    errors.append(f"{where}: {exe} {key} {value}, but {seen[key][0]} has "
                                  f"{seen[key][1]}")
                seen.setdefault(key, (where, value))
        if exe == "lightfarm-worker" and "systemd" in deployments and exe in deployments["systemd"]:
            where, args = deployments["systemd"][exe]
            cache = flag_values(args).get("--cache-dir", "")
            if not cache.startswith("/var/cache/lightfarm/"):
                errors.append(f"{where}: --cache-dir {cache} is not under /var/cache/lightfarm")


# ---------------------------------------------------------------- a real server

def read_lines(proc, lines):
    for line in proc.stdout:
        lines.append(line.strip())


def check_live(pki, compose_found, k8s_found, systemd_found):
    """docs/deploy.md's certificates with a real server: TLS, worker certificates, tokens,
    the Compose health check and the HPA's metric."""
    if pki is None:
        return
    data = os.path.join(TMP, "live-data")
    os.makedirs(data)
    # The certificate names every --server host of the deployments.
    names = san_names(pki["server.crt"])
    for label, found in (("compose", compose_found), ("kubernetes", k8s_found),
                         ("systemd", systemd_found)):
        if "lightfarm-worker" in found:
            where, args = found["lightfarm-worker"]
            host = host_of(flag_values(args).get("--server"))
            if host and host not in names:
                errors.append(f"{rel(DOCS)}: the server certificate's names {sorted(names)} miss "
                              f"{host}, the --server of {where}")
    admin = subprocess.run([binary("lightfarm-server"), "token", "create", "--data-dir", data,
                            "--name", "check-admin", "--role", "admin"],
                           capture_output=True, text=True, timeout=60)
    worker = subprocess.run([binary("lightfarm-server"), "token", "create", "--data-dir", data,
                             "--name", "check-worker", "--role", "worker"],
                            capture_output=True, text=True, timeout=60)
    if admin.returncode or worker.returncode:
        errors.append(f"lightfarm-server token create fails: {admin.stderr}{worker.stderr}")
        return
    tokens = {}
    for name, r in (("admin", admin), ("worker", worker)):
        tokens[name] = os.path.join(TMP, f"{name}.token")
        with open(tokens[name], "w") as out:
            out.write(r.stdout.strip().splitlines()[-1] + "\n")
    server = subprocess.Popen(
        [binary("lightfarm-server"), "--listen", "127.0.0.1:0", "--http", "127.0.0.1:0",
         "--data-dir", data, "--tls-cert", pki["server.crt"], "--tls-key", pki["server.key"],
         "--tls-client-ca", pki["ca.crt"]],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    procs = [server]
    try:
        lines = []
        threading.Thread(target=read_lines, args=(server, lines), daemon=True).start()
        deadline = time.time() + 20
        while time.time() < deadline and not any(l.startswith("http on") for l in lines):
            if server.poll() is not None:
                break
            time.sleep(0.05)
        grpc = next((port_of(l.split()[-1]) for l in lines if l.startswith("listening on")), None)
        http = next((port_of(l.split()[-1]) for l in lines if l.startswith("http on")), None)
        if not grpc or not http:
            errors.append(f"{rel(DOCS)}: a server with its certificates did not start: {lines}")
            return
        # With --tls-cert, --http speaks HTTPS with the same certificate (names 127.0.0.1).
        tls = ssl.create_default_context(cafile=pki["ca.crt"])
        metrics = urllib.request.urlopen(f"https://127.0.0.1:{http}/metrics", timeout=10,
                                         context=tls).read()
        if not re.search(rf"^{HPA_METRIC}\b", metrics.decode(), re.M):
            errors.append(f"{rel(K8S)}/worker-hpa.yaml: the server's /metrics has no {HPA_METRIC}")
        test = compose_found.get("healthcheck")
        if test and shutil.which("bash"):
            script = [re.sub(r"127\.0\.0\.1([/:])8080", rf"127.0.0.1\g<1>{http}", t)
                      for t in test[1:]]
            r = subprocess.run(script, capture_output=True, text=True, timeout=20)
            if r.returncode != 0:
                errors.append(f"{rel(COMPOSE)}: the server's healthcheck fails against a real "
                              f"server ({r.returncode}): {r.stderr.strip()}")
        # A worker with the docs' client certificate and a worker token, on the name localhost.
        w = subprocess.Popen(
            [binary("lightfarm-worker"), "--server", f"localhost:{grpc}", "--tls-ca",
             pki["ca.crt"], "--tls-cert", pki["worker.crt"], "--tls-key", pki["worker.key"],
             "--token-file", tokens["worker"], "--name", "check-deploy-worker", "--threads", "1",
             "--cache-dir", os.path.join(TMP, "live-cache")],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        procs.append(w)
        listed = ""
        deadline = time.time() + 20
        while time.time() < deadline and "check-deploy-worker" not in listed:
            r = subprocess.run([binary("lightfarm"), "workers", "--server", f"localhost:{grpc}",
                                "--tls-ca", pki["ca.crt"], "--token-file", tokens["admin"]],
                               capture_output=True, text=True, timeout=30)
            listed = r.stdout + r.stderr
            time.sleep(0.3)
        if "check-deploy-worker" not in listed:
            errors.append(f"{rel(DOCS)}: a worker with the docs' client certificate and a worker "
                          f"token never appears in `lightfarm workers` ({listed.strip()[-400:]})")
    finally:
        stop_all(procs)


def main():
    for exe in ("lightfarm-server", "lightfarm-worker", "lightfarm"):
        if not os.access(binary(exe), os.X_OK):
            print(f"check_deploy: {binary(exe)} is missing: build first", file=sys.stderr)
            return 1
    try:
        docs = check_yaml_parses()
        pki = make_pki()
        stages = parse_dockerfile()
        images = check_dockerfile(stages, pki)
        compose_found = check_compose(docs, images, pki)
        k8s_found = check_kubernetes(docs, images, pki)
        systemd_found = check_systemd(pki)
        check_agreement({"compose": compose_found, "kubernetes": k8s_found,
                         "systemd": systemd_found,
                         "docker": {i["exe"]: (f"{rel(DOCKERFILE)} (target {t} CMD)", i["cmd"])
                                    for t, i in images.items()}})
        check_live(pki, compose_found, k8s_found, systemd_found)
    finally:
        shutil.rmtree(TMP, ignore_errors=True)
    for e in errors:
        print("FAIL", e)
    print(f"check_deploy: {len(errors)} problem(s)" if errors else "check_deploy: all agree")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
