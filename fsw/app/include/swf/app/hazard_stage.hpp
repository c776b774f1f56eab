// MapperHazardStage: the hazard group's work (issue 8 wired into issue 6). Runs
// swf::hazard::HazardMapper on the snapshot the frame group took (rectified pair, newest pose with
// its covariance, landmarks with covariances) and fills the hazard_map_t record. Flight code:
// everything is allocated by Configure(); Process() does not allocate.
#pragma once

#include <memory>

#include "swf/app/flight_loop.hpp"
#include "swf/hazard/hazard_mapper.hpp"

namespace swf::app {

// hazard_map_t.CLASS_* of a mapper class. kUncertain is its own class (CLASS_UNCERTAIN), never
// safe.
std::int8_t HazardClassCode(hazard::HazardClass k);

// The mapper's current map into *out as the hazard group publishes it (grid, per-cell layers with
// class codes, safe site); utime, frame_seq and update_ms are the caller's. kFull when the grid
// exceeds out->capacity_cells. The one conversion from mapper state to a published map: the
// ground tools (tools/hazard) publish through it too, so what they evaluate is what guidance gets.
// Does not allocate.
core::Status FillHazardRecord(const hazard::HazardMapper& mapper, HazardRecord* out);

class MapperHazardStage final : public HazardStage {
 public:
  // Allocates the mapper (options.camera and image size must be those of the rectified pair).
  core::Status Configure(const hazard::HazardMapperOptions& options);
  core::Status Process(const HazardInput& input, HazardRecord* out) override;
  const hazard::HazardMapper& Mapper() const { return *mapper_; }
  std::int32_t GridCells() const { return mapper_ ? mapper_->GridCells() : 0; }
  std::int64_t Errors() const { return errors_; }

 private:
  std::unique_ptr<hazard::HazardMapper> mapper_;
  std::int64_t errors_ = 0;
};

}  // namespace swf::app
