// Compiled filter instances (see kitti_vo_instance.hpp), all in one translation unit: the first
// SlidingWindowFilter instance a translation unit compiles pays for most of the Eigen machinery
// every later one reuses, so one unit costs far less than one per group of tiers.
#include "kitti_vo_instance.hpp"

namespace swf::tools::detail {

// Batch solves up to 128 poses.
KittiVoTier TierBatch32() { return MakeTier<32, 4096, 512, 1>("batch-32"); }
KittiVoTier TierBatch128() { return MakeTier<128, 32768, 1024, 1>("batch-128"); }

// Batch solves of long sequences. Most of their memory is the window's per-pose measurement slots
// and the dense pose blocks (the covariance workspace and the reduced system grow with K^2), so K
// grows by ~4x per tier.
KittiVoTier TierBatch512() { return MakeTier<512, 131072, 2048, 1>("batch-512"); }
KittiVoTier TierBatch2048() { return MakeTier<2048, 524288, 2048, 1>("batch-2048"); }
KittiVoTier TierBatch4800() { return MakeTier<4800, 2097152, 1024, 1>("batch-4800"); }

// Sliding windows. The prior is dense over the oldest pose and the prior landmarks, so P (3P x 3P
// doubles, twice: the prior and the marginalization workspace) dominates their memory.
KittiVoTier TierWindow32() { return MakeTier<32, 4096, 512, 512>("window-32"); }
KittiVoTier TierWindow32Wide() { return MakeTier<32, 16384, 1024, 1024>("window-32-wide"); }
KittiVoTier TierWindow128() { return MakeTier<128, 65536, 2048, 4096>("window-128"); }

}  // namespace swf::tools::detail
