#!/usr/bin/env python3
"""Renders docker/nginx/pathd.conf.template, the nginx load balancer in front
of several pathd replicas, for one topology.

  render_nginx_conf.py render --listen ADDR --upstream HOST:PORT [...]
                              --runtime_dir DIR [--error_log F] [--access_log F]
                              [--single_process] [-o FILE]
      one nginx.conf (stdout without -o); the loopback test uses this.
  render_nginx_conf.py deploy [--replicas N] [--check]
      the files docker/compose.yaml and docker/k8s use, for N replicas
      (default 3): docker/nginx/compose.conf, docker/k8s/nginx-configmap.yaml
      and docker/k8s/pathd-replica-services.yaml. With --check nothing is
      written; exit 1 if a file differs from its rendering.
"""

import argparse
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
TEMPLATE = ROOT / "docker/nginx/pathd.conf.template"
COMPOSE_CONF = ROOT / "docker/nginx/compose.conf"
K8S_CONFIGMAP = ROOT / "docker/k8s/nginx-configmap.yaml"
DEFAULT_REPLICAS = 3
# The port pathd listens on in its container, and the balancer's port. The
# balancer runs as an unprivileged user, so not 80/443.
PATHD_PORT = 50051
BALANCER_PORT = 8080

GENERATED_NOTE = ("# Generated from docker/nginx/pathd.conf.template by\n"
                  "# scripts/render_nginx_conf.py {command}; do not edit.\n")


def render(listen, upstreams, runtime_dir, error_log, access_log,
           single_process=False, command="render"):
    """The template with every @NAME@ placeholder filled in."""
    if not upstreams:
        raise ValueError("at least one --upstream is needed")
    for upstream in upstreams:
        # A server line is "HOST:PORT"; anything else would inject directives.
        if not re.fullmatch(r"[A-Za-z0-9._\-\[\]:]+:\d+", upstream):
            raise ValueError(f"--upstream '{upstream}' is not HOST:PORT")
    servers = "\n".join(f"        server {u} max_fails=0;" for u in upstreams)
    values = {
        # A test wants one process it can kill: nginx's workers are not told
        # when their master is killed, so they would outlive a crashed test.
        "PROCESS_MODEL": ("master_process off;" if single_process
                          else "worker_processes auto;"),
        "LISTEN": listen,
        "SERVERS": servers,
        "RUNTIME_DIR": runtime_dir,
        "ERROR_LOG": error_log,
        # The log format is defined in the template; "off" takes none.
        "ACCESS_LOG": access_log if access_log == "off" else f"{access_log} pathd",
    }
    text = TEMPLATE.read_text()
    unknown = set(re.findall(r"@([A-Z_]+)@", text)) - set(values)
    if unknown:
        raise ValueError(f"{TEMPLATE}: unknown placeholders {sorted(unknown)}")
    for name, value in values.items():
        text = text.replace(f"@{name}@", value)
    return GENERATED_NOTE.format(command=command) + text


def compose_conf(replicas):
    # docker/compose.yaml names the replicas pathd-1 .. pathd-N. The container
    # logs to stdout/stderr (docker logs) and keeps its runtime files in /tmp.
    return render(
        listen=f"0.0.0.0:{BALANCER_PORT}",
        upstreams=[f"pathd-{i}:{PATHD_PORT}" for i in range(1, replicas + 1)],
        runtime_dir="/tmp", error_log="stderr", access_log="/dev/stdout",
        command=f"deploy --replicas {replicas}")


def k8s_configmap(replicas):
    # docker/k8s/pathd.yaml gives each StatefulSet pod pathd-0 .. pathd-(N-1)
    # its own ClusterIP Service of the same name: a stable address, where the
    # pod IP behind the headless Service changes when the pod is rescheduled
    # and nginx resolves upstream names only when it starts.
    conf = render(
        listen=f"0.0.0.0:{BALANCER_PORT}",
        upstreams=[f"pathd-{i}:{PATHD_PORT}" for i in range(replicas)],
        runtime_dir="/tmp", error_log="stderr", access_log="/dev/stdout",
        command=f"deploy --replicas {replicas}")
    body = "".join(f"    {line}".rstrip() + "\n" for line in conf.splitlines())
    return (GENERATED_NOTE.format(command=f"deploy --replicas {replicas}") +
            "apiVersion: v1\n"
            "kind: ConfigMap\n"
            "metadata:\n"
            "  name: pathd-balancer\n"
            "data:\n"
            "  nginx.conf: |\n" + body)


def k8s_replica_services(replicas):
    docs = []
    for i in range(replicas):
        docs.append(
            "apiVersion: v1\n"
            "kind: Service\n"
            "metadata:\n"
            f"  name: pathd-{i}\n"
            "spec:\n"
            "  selector:\n"
            "    app: pathd\n"
            f"    statefulset.kubernetes.io/pod-name: pathd-{i}\n"
            "  ports:\n"
            "    - name: grpc\n"
            f"      port: {PATHD_PORT}\n")
    return (GENERATED_NOTE.format(command=f"deploy --replicas {replicas}") +
            "# One stable Service per pathd pod, the balancer's upstreams.\n" +
            "---\n".join(docs))


def deploy(replicas, check):
    if replicas < 1:
        raise ValueError(f"--replicas must be >= 1, not {replicas}")
    files = {
        COMPOSE_CONF: compose_conf(replicas),
        K8S_CONFIGMAP: k8s_configmap(replicas),
        ROOT / "docker/k8s/pathd-replica-services.yaml":
            k8s_replica_services(replicas),
    }
    stale = []
    for path, text in files.items():
        current = path.read_text() if path.exists() else None
        if current == text:
            continue
        if check:
            stale.append(path.relative_to(ROOT))
        else:
            path.write_text(text)
            print(f"wrote {path.relative_to(ROOT)}")
    if stale:
        print("out of date with docker/nginx/pathd.conf.template: " +
              ", ".join(map(str, stale)) +
              f"; run scripts/render_nginx_conf.py deploy --replicas {replicas}",
              file=sys.stderr)
        return 1
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    one = sub.add_parser("render", help="render one nginx.conf")
    one.add_argument("--listen", required=True, help="HOST:PORT nginx listens on")
    one.add_argument("--upstream", action="append", default=[],
                     help="HOST:PORT of a pathd replica (repeat per replica)")
    one.add_argument("--runtime_dir", required=True,
                     help="writable directory for the pid file and temp files")
    one.add_argument("--error_log", default="stderr")
    one.add_argument("--access_log", default="off")
    one.add_argument("--single_process", action="store_true",
                     help="one nginx process, no workers (for tests)")
    one.add_argument("-o", "--output", help="file to write (default stdout)")
    dep = sub.add_parser("deploy", help="render the compose and k8s files")
    dep.add_argument("--replicas", type=int, default=DEFAULT_REPLICAS)
    dep.add_argument("--check", action="store_true",
                     help="write nothing; exit 1 when a file is out of date")
    args = parser.parse_args()
    try:
        if args.command == "deploy":
            return deploy(args.replicas, args.check)
        text = render(args.listen, args.upstream, args.runtime_dir,
                      args.error_log, args.access_log, args.single_process)
    except (ValueError, OSError) as error:
        print(f"render_nginx_conf.py: {error}", file=sys.stderr)
        return 2
    if args.output:
        pathlib.Path(args.output).write_text(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
