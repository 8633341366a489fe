#!/usr/bin/env bash
# A two-node Ray cluster on one machine, then RLlib's PPO on mapc across it (docs/python.md, "A Ray cluster").
#
# The head and the worker are separate Ray nodes, each started with `ray start` in its own network namespace; the
# namespaces are joined by a veth pair (head 10.77.0.1/24, worker 10.77.0.2/24) and have no other interface but
# their loopback, so every packet of the cluster stays on that pair or on a loopback. Ray's token authentication
# is on: a random token, readable only by root, that the nodes and the driver load from RAY_AUTH_TOKEN_PATH; a
# client without it is shown refused. The driver (in the head's namespace) trains a few PPO iterations with one env
# runner per node, each stepping mapc's vector env, prints which node each runner is on, writes the policy as a
# mapc policy file, and `mapc eval` evaluates that file. On exit, whatever happened, the script kills the
# processes in its namespaces (by their ids), deletes the namespaces (the veth pair goes with them) and its
# temporary folder.
#
#   sudo tools/ray_cluster/run.sh                 # as root (network namespaces); ITERS=2 BATCH=8000 by default
#
# Environment: VENV (default target/ray-py: made on first use with `pip install ./python "ray[rllib]" torch`;
# after changing mapc's sources, `MATURIN_PEP517_ARGS="--profile dev" $VENV/bin/pip install --no-build-isolation
# ./python` brings it up to date), OUT (default out/ray_cluster), ITERS, BATCH, ENVS_PER_RUNNER, EVAL_SEEDS.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
VENV=${VENV:-$ROOT/target/ray-py}
OUT=${OUT:-$ROOT/out/ray_cluster}
ITERS=${ITERS:-2}
BATCH=${BATCH:-8000}
ENVS_PER_RUNNER=${ENVS_PER_RUNNER:-2}
EVAL_SEEDS=${EVAL_SEEDS:-10}
HEAD_IP=10.77.0.1
WORKER_IP=10.77.0.2
PORT=6379

[ "$(id -u)" -eq 0 ] || { echo "run.sh: network namespaces need root (sudo $0)" >&2; exit 2; }
command -v ip >/dev/null || { echo "run.sh: the ip command (iproute2) is missing" >&2; exit 2; }

# The Python side: one venv, made once (torch alone is a few GB) and reused. The package is built in the dev
# profile, which reuses `cargo build`'s dependencies.
if ! "$VENV/bin/python" -c "import ray.rllib, torch, mapc.rllib" 2>/dev/null; then
  echo "== making $VENV (pip install ./python \"ray[rllib]\" torch; minutes the first time)"
  [ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q maturin "ray[rllib]" torch
  PATH="$VENV/bin:$PATH" MATURIN_PEP517_ARGS="--profile dev" \
    nice -n 5 "$VENV/bin/pip" install -q --no-build-isolation ./python
fi
MAPC=$ROOT/target/debug/mapc
[ -x "$MAPC" ] || nice -n 5 cargo build --locked --bin mapc

RUN_ID=$$
NS_HEAD=mapc-ray-head-$RUN_ID
NS_WORKER=mapc-ray-worker-$RUN_ID
VETH_HEAD=mapcrh$RUN_ID
VETH_WORKER=mapcrw$RUN_ID
# short: Ray's unix sockets live under the temp folder and a socket path has at most 107 bytes
TMP=$(mktemp -d /tmp/mapc-ray.XXXXXX)

cleanup() {
  local rc=$?
  set +e
  for ns in "$NS_HEAD" "$NS_WORKER"; do
    ip netns list | grep -qw "$ns" || continue
    # every process in our namespaces is one this script started (Ray's daemons and workers included)
    pids=$(ip netns pids "$ns")
    [ -n "$pids" ] && kill $pids 2>/dev/null
  done
  for _ in $(seq 20); do
    left=""
    for ns in "$NS_HEAD" "$NS_WORKER"; do
      ip netns list | grep -qw "$ns" && left+=$(ip netns pids "$ns")
    done
    [ -z "$left" ] && break
    sleep 0.5
  done
  for ns in "$NS_HEAD" "$NS_WORKER"; do
    ip netns list | grep -qw "$ns" || continue
    pids=$(ip netns pids "$ns")
    [ -n "$pids" ] && kill -9 $pids 2>/dev/null
    ip netns delete "$ns"
  done
  rm -rf "$TMP"
  echo "== cleaned up: processes stopped, namespaces $NS_HEAD and $NS_WORKER and their veth pair removed"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "== network: $NS_HEAD ($HEAD_IP) <-veth-> $NS_WORKER ($WORKER_IP), loopback up in each, no other route"
ip netns add "$NS_HEAD"
ip netns add "$NS_WORKER"
ip link add "$VETH_HEAD" type veth peer name "$VETH_WORKER"
ip link set "$VETH_HEAD" netns "$NS_HEAD"
ip link set "$VETH_WORKER" netns "$NS_WORKER"
ip -n "$NS_HEAD" addr add "$HEAD_IP/24" dev "$VETH_HEAD"
ip -n "$NS_WORKER" addr add "$WORKER_IP/24" dev "$VETH_WORKER"
for ns in "$NS_HEAD" "$NS_WORKER"; do ip -n "$ns" link set lo up; done
ip -n "$NS_HEAD" link set "$VETH_HEAD" up
ip -n "$NS_WORKER" link set "$VETH_WORKER" up

# Token authentication: RAY_AUTH_MODE=token on every node and client; the token is read from a root-only file
python3 -c "import secrets; print(secrets.token_hex(32))" > "$TMP/auth_token"
chmod 600 "$TMP/auth_token"
RAY_ENV=(env RAY_AUTH_MODE=token RAY_AUTH_TOKEN_PATH="$TMP/auth_token" RAY_USAGE_STATS_ENABLED=0
         PATH="$VENV/bin:$PATH")
in_ns() { local ns=$1; shift; ip netns exec "$ns" "${RAY_ENV[@]}" "$@"; }

echo "== ray start --head in $NS_HEAD"
# one CPU per node: the two env runners (one CPU each) then run one on each node
in_ns "$NS_HEAD" ray start --head --node-ip-address="$HEAD_IP" --port="$PORT" --num-cpus=1 \
  --include-dashboard=false --disable-usage-stats --object-store-memory=200000000 --temp-dir="$TMP/h" \
  >"$TMP/head.log" 2>&1 || { cat "$TMP/head.log"; exit 1; }
grep -E "Local node IP|Ray runtime started" "$TMP/head.log" | sed 's/^ */  /'
echo "== ray start --address=$HEAD_IP:$PORT in $NS_WORKER"
in_ns "$NS_WORKER" ray start --address="$HEAD_IP:$PORT" --node-ip-address="$WORKER_IP" --num-cpus=1 \
  --object-store-memory=200000000 --temp-dir="$TMP/w" --disable-usage-stats \
  >"$TMP/worker.log" 2>&1 || { cat "$TMP/worker.log"; exit 1; }
grep -E "Local node IP|Ray runtime started" "$TMP/worker.log" | sed 's/^ */  /'

echo "== the cluster's nodes (a client with the token)"
in_ns "$NS_HEAD" python - "$HEAD_IP:$PORT" <<'EOF'
import sys, time
import ray
ray.init(address=sys.argv[1], log_to_driver=False)
for _ in range(60):
    nodes = [n for n in ray.nodes() if n["Alive"]]
    if len(nodes) >= 2:
        break
    time.sleep(0.5)
for n in nodes:
    print(f"  node {n['NodeManagerAddress']}: {n['Resources'].get('CPU', 0):.0f} CPU, id {n['NodeID'][:12]}")
assert len(nodes) == 2, "the worker node did not join"
EOF

echo "== a client without the token is refused"
if ip netns exec "$NS_WORKER" env RAY_AUTH_MODE=token RAY_AUTH_TOKEN=not-the-token PATH="$VENV/bin:$PATH" \
   timeout 60 python -c "import ray, sys; ray.init(address=sys.argv[1], log_to_driver=False)" "$HEAD_IP:$PORT" \
   >"$TMP/refused.log" 2>&1; then
  echo "run.sh: a client with a wrong token joined the cluster" >&2; exit 1
fi
grep -m1 -oE "[A-Za-z]*(Authentication|Unauthenticated|UNAUTHENTICATED)[^.]*" "$TMP/refused.log" | sed 's/^/  /' \
  || tail -n 2 "$TMP/refused.log" | sed 's/^/  /'

echo "== RLlib PPO across the cluster: 2 env runners x $ENVS_PER_RUNNER sub-environments, $ITERS iterations"
mkdir -p "$OUT"
in_ns "$NS_HEAD" python examples/python/rllib_ppo.py --address "$HEAD_IP:$PORT" --env-runners 2 \
  --envs-per-runner "$ENVS_PER_RUNNER" --iters "$ITERS" --batch "$BATCH" --eval-seeds 2 --out "$OUT"

echo "== mapc eval --policy $OUT/policy.json --seeds $EVAL_SEEDS"
"$MAPC" eval --policy "$OUT/policy.json" --seeds "$EVAL_SEEDS"
