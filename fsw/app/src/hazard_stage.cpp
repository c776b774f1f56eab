#include "swf/app/hazard_stage.hpp"

#include <new>

namespace swf::app {

using core::Status;

std::int8_t HazardClassCode(hazard::HazardClass k) {
  switch (k) {
    case hazard::HazardClass::kSafe: return 1;
    case hazard::HazardClass::kSlope: return 2;
    case hazard::HazardClass::kRock: return 3;
    case hazard::HazardClass::kUncertain: return 5;
    case hazard::HazardClass::kUnknown: return 0;
  }
  return 0;
}

Status FillHazardRecord(const hazard::HazardMapper& m, HazardRecord* out) {
  const std::int32_t n = m.GridCells();
  const std::int32_t cells = n * n;
  if (cells > out->capacity_cells) return Status::kFull;
  out->origin_world_m[0] = m.CornerX();
  out->origin_world_m[1] = m.CornerY();
  out->cell_size_m = m.CellM();
  out->cells_per_side = n;
  for (std::int32_t c = 0; c < cells; ++c) {
    out->elevation_m[c] = m.Elevation()[c];
    out->sigma_m[c] = m.Sigma()[c];
    out->relief_sigma_m[c] = m.ReliefSigma()[c];
    out->slope_deg[c] = m.SlopeDeg()[c];
    out->roughness_m[c] = m.Roughness()[c];
    out->hazard_class[c] = HazardClassCode(m.Classes()[c]);
  }
  const hazard::SafeSite& site = m.Site();
  out->safe_site_valid = site.valid;
  out->safe_site_world_m[0] = site.position_world_m.x();
  out->safe_site_world_m[1] = site.position_world_m.y();
  out->safe_site_score = site.score;
  out->outliers_rejected = static_cast<std::int64_t>(m.Stats().outliers_rejected);
  out->cells_replaced = static_cast<std::int64_t>(m.Stats().cells_replaced);
  return Status::kOk;
}

Status MapperHazardStage::Configure(const hazard::HazardMapperOptions& options) {
  mapper_.reset(new (std::nothrow) hazard::HazardMapper());
  if (!mapper_) return Status::kFull;
  return mapper_->Configure(options);
}

Status MapperHazardStage::Process(const HazardInput& input, HazardRecord* out) {
  if (!mapper_ || !input.pose_valid) {
    ++errors_;
    return Status::kNotConfigured;
  }
  hazard::HazardFrame f;
  f.left = frontend::GrayView{input.left.get(), input.width, input.height, input.width};
  f.right = frontend::GrayView{input.right.get(), input.width, input.height, input.width};
  f.world_T_camera = input.world_T_camera;
  f.pose_covariance = input.pose_covariance;
  f.landmarks = input.landmarks;
  f.num_landmarks = input.num_landmarks;
  const Status s = mapper_->Update(f);
  if (s != Status::kOk) {
    ++errors_;
    return s;
  }
  if (FillHazardRecord(*mapper_, out) != Status::kOk) {
    ++errors_;
    return Status::kFull;
  }
  out->utime = input.utime;
  out->frame_seq = input.frame_seq;
  return Status::kOk;
}

}  // namespace swf::app
