// Layering guard (ARCHITECTURE.md): flight libraries may not talk to camera drivers; that is drivers/.
#error "layering violation: <aravis-0.8/arv.h> included from a flight library"
