// Layering guard (ARCHITECTURE.md): flight libraries may not talk to camera drivers; that is drivers/.
#error "layering violation: <libv4l2.h> included from a flight library"
