#!/bin/sh
# Lints the recipes: shellcheck on every script, the Kubernetes manifests against the
# API's schemas (kubernetes-validate, offline; `kubectl --dry-run=client` needs a
# cluster to fetch them from), and the shard count agreeing between the render Job and
# the merge Job. Needs shellcheck (apt) and kubernetes-validate (pip); `cargo test`
# runs this and skips with a message where they are missing (CI installs them).
set -eu
here=$(cd "$(dirname "$0")" && pwd)

shellcheck "$here"/*.sh "$here"/*/*.sh
kubernetes-validate --quiet --strict --kubernetes-version "${K8S_VERSION:-1.31.0}" "$here"/kubernetes/*.yaml

python3 - "$here/kubernetes" <<'PY'
import sys, yaml
d = sys.argv[1]
render = yaml.safe_load(open(f"{d}/render-job.yaml"))
merge = yaml.safe_load(open(f"{d}/merge-job.yaml"))
def env(job, name):
    c = job["spec"]["template"]["spec"]["containers"][0]
    return next(e["value"] for e in c.get("env", []) if e["name"] == name)
spec = render["spec"]
problems = []
if spec.get("completionMode") != "Indexed":
    problems.append("render-job.yaml: completionMode must be Indexed (JOB_COMPLETION_INDEX picks the shard)")
if str(spec["completions"]) != env(render, "SHARDS"):
    problems.append(f"render-job.yaml: completions {spec['completions']} but SHARDS {env(render, 'SHARDS')}")
if env(merge, "SHARDS") != env(render, "SHARDS"):
    problems.append(f"merge-job.yaml merges {env(merge, 'SHARDS')} shards, render-job.yaml renders {env(render, 'SHARDS')}")
claims = {v["persistentVolumeClaim"]["claimName"] for j in (render, merge) for v in j["spec"]["template"]["spec"]["volumes"]}
pvc = yaml.safe_load(open(f"{d}/work-volume.yaml"))["metadata"]["name"]
if claims != {pvc}:
    problems.append(f"the Jobs mount {sorted(claims)}, work-volume.yaml defines {pvc}")
for p in problems:
    print(p, file=sys.stderr)
sys.exit(1 if problems else 0)
PY
echo "deploy/: scripts and manifests pass"
