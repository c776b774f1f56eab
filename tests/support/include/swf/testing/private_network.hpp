// Tests that use the network (LCM over UDP multicast, GigE Vision) run in a network namespace of
// their own, with only loopback, so that nothing leaves the machine and parallel tests do not
// hear each other (RECIPES.md).
#pragma once

namespace swf::testing {

// Moves the calling process into a new network namespace (as root, or through an unprivileged
// user namespace otherwise), brings loopback up and runs `setup` (a shell command: a multicast
// route, an extra address). Call it before any thread exists, e.g. to initialize a global:
// unshare applies to the calling thread only. False when any step failed.
bool EnterPrivateNetwork(const char* setup);

}  // namespace swf::testing
