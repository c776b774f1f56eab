// Compiled filter instances for sliding windows (see kitti_vo_instance.hpp). The prior is dense
// over the oldest pose and the prior landmarks, so P (3P x 3P doubles, twice: the prior and the
// marginalization workspace) dominates their memory.
#include "kitti_vo_instance.hpp"

namespace swf::tools::detail {

KittiVoTier TierWindow32() { return MakeTier<32, 4096, 512, 512>("window-32"); }
KittiVoTier TierWindow32Wide() { return MakeTier<32, 16384, 1024, 1024>("window-32-wide"); }
KittiVoTier TierWindow128() { return MakeTier<128, 65536, 2048, 4096>("window-128"); }

}  // namespace swf::tools::detail
