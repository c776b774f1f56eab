// Layering guard (ARCHITECTURE.md): flight libraries may not talk to V4L2; that is drivers/.
#error "layering violation: <linux/videodev2.h> included from a flight library"
