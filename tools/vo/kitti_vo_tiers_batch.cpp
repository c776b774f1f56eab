// Compiled filter instances for batch solves up to 128 poses (see kitti_vo_instance.hpp).
#include "kitti_vo_instance.hpp"

namespace swf::tools::detail {

KittiVoTier TierBatch32() { return MakeTier<32, 4096, 512, 1>("batch-32"); }
KittiVoTier TierBatch128() { return MakeTier<128, 32768, 1024, 1>("batch-128"); }

}  // namespace swf::tools::detail
