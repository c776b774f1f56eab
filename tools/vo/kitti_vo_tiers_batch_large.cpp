// Compiled filter instances for batch solves of long sequences (see kitti_vo_instance.hpp).
// Most of their memory is the window's per-pose measurement slots and the dense pose blocks
// (the covariance workspace and the reduced system grow with K^2), so K grows by ~4x per tier.
#include "kitti_vo_instance.hpp"

namespace swf::tools::detail {

KittiVoTier TierBatch512() { return MakeTier<512, 131072, 2048, 1>("batch-512"); }
KittiVoTier TierBatch2048() { return MakeTier<2048, 524288, 2048, 1>("batch-2048"); }
KittiVoTier TierBatch4800() { return MakeTier<4800, 2097152, 1024, 1>("batch-4800"); }

}  // namespace swf::tools::detail
