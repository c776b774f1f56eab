// Layering guard (ARCHITECTURE.md): flight libraries (fsw/core, estimator, fsw/frontend,
// fsw/hazard) may not use LCM. Publish through fsw/app, which is the only place that wires
// middleware to computation.
#error "layering violation: LCM header <lcm/eventlog.h> included from a flight library"
