# Sourced by the tests that fly swf-fsw on Aravis's GigE Vision fake cameras (aravis_test.sh,
# bench_gige_test.sh), after setting `here` to their directory: the private network namespace
# (tests/support/sh/private_network.sh, with fail and json), a scratch directory removed at exit,
# and the log comparer.
private_network_sh="$(cd "$here/../../../tests/support/sh" && pwd)/private_network.sh"
. "$private_network_sh"
choose_private_network || fail "cannot create a network namespace (root or unprivileged userns)"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cmp="/usr/bin/python3 $here/log_compare.py"
# in_gige_namespace PROGRAM ARGS...: the program in the namespace, loopback up and carrying the
# fake cameras' two addresses (127.0.0.1, 127.0.0.2).
in_gige_namespace() {
  $ns sh -c 'ip link set lo up && ip addr add 127.0.0.2/8 dev lo && exec "$0" "$@"' "$@"
}
