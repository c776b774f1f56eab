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
