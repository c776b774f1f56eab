# Shell helpers for the tests that run programs over LCM UDP multicast in a private network
# namespace whose only interface is loopback (RECIPES.md; private_network.hpp is the C++ side).
# Sourced, by the test script and again inside the namespace's shell:
#   . "$(dirname "$0")/../../../tests/support/sh/private_network.sh"

fail() { echo "FAIL: $*" >&2; exit 1; }

# Sets $dir to a new scratch directory, removed at exit unless KEEP is set (to look into after a
# failure).
make_scratch_dir() {
  dir=$(mktemp -d)
  trap '[ -n "${KEEP:-}" ] || rm -rf "$dir"' EXIT
}

# Sets $ns to the command that runs its arguments in a new network namespace: `unshare -n` as
# root, an unprivileged user namespace otherwise. Fails (status 1) where neither can be made.
choose_private_network() {
  if [ "$(id -u)" -eq 0 ]; then ns="unshare -n"; else ns="unshare -rn"; fi
  $ns true 2>/dev/null
}

# Inside the namespace: loopback up, with LCM's multicast group routed over it.
multicast_on_loopback() {
  ip link set lo up && ip route add 239.0.0.0/8 dev lo
}

# Inside the namespace: starts swf-view ($1) on a free port with its summary in $2/view.json and
# its errors in $2/view.err; sets $v to its pid and, once it serves (5 s at most), $url.
start_view() {
  "$1" --port 0 --url-file "$2/url" > "$2/view.json" 2> "$2/view.err" &
  v=$!
  for i in $(seq 50); do [ -s "$2/url" ] && break; sleep 0.1; done
  url=$(cat "$2/url")
}

# json FILE EXPRESSION: prints the Python expression over the JSON document d read from FILE.
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
