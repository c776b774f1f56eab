// TimeOffsetEstimator: the camera-IMU time offset, estimated online from the process factors of
// the stereo-inertial filter (inertial_model.hpp).
//
// The offset tau: the IMU stamps an instant t as t + tau on the camera's clock, so the samples a
// state at exposure t needs end at t + tau. The flight pipeline integrates each interval to the
// exposure plus the current estimate tau_a (the applied offset); should the true offset differ
// by d, the interval is off by d at both ends and its process residual by
//     e(d) ~ e + J_tau d       (J_tau = InertialStereoModel::ProcessTimeShiftJacobian)
// which only a changing rate or force shows (the jitter and lever arm of a descent do).
//
// One interval after the solve. With r = W e and g = W J_tau whitened by the factor's
// square-root information W, the offset left in the interval is read as
//     d = -(g^T r) / (g^T g)
// (least squares on r = g d + noise). The residual is taken at the solved states, and those
// already took part of the offset's effect into themselves (the factor is in the solve): d is
// the remaining offset times a share k in (0, 1], the larger the better the images fix the
// states against the IMU. (The exact share needs the newest state's covariance conditioned on
// the one before, which the filter does not keep; its marginal covariance carries the whole
// path's drift and gave a share of zero.) So the estimate integrates the readings,
//     tau <- tau + d,
// and the next intervals are integrated at it: the remaining offset shrinks by (1 - k) per
// interval, to zero at a rate the images set, and with noise of variance var(d) / (k (2 - k)).
// Each reading is clipped to +-max_offset_s and the estimate held within it (a failed frame must
// not throw the estimate). SigmaS states the information the readings carried (fading memory of
// memory_intervals intervals), a lower bound of the estimate's uncertainty. Fixed size, no
// allocation, O(15^2) per interval.
#pragma once

#include <algorithm>
#include <cmath>

#include "swf/core/status.hpp"
#include "swf/estimator/inertial_model.hpp"

namespace swf::estimator {

template <typename S>
struct TimeOffsetOptions {
  S initial_offset_s = S(0);   // the offset the estimate starts from (a calibration's)
  S prior_sigma_s = S(0.01);   // its uncertainty
  S max_offset_s = S(0.05);    // the estimate and every reading are held within +-this
  S memory_intervals = S(50);  // fading memory: a reading's weight is 1/e after this many
  bool Valid() const {
    return std::isfinite(initial_offset_s) && prior_sigma_s > S(0) &&
           std::isfinite(prior_sigma_s) && max_offset_s > S(0) && std::isfinite(max_offset_s) &&
           std::abs(initial_offset_s) <= max_offset_s && memory_intervals >= S(1) &&
           std::isfinite(memory_intervals);
  }
};

template <typename S>
class TimeOffsetEstimator {
 public:
  // kInvalidArgument (nothing changed) for options that are not Valid().
  core::Status Configure(const TimeOffsetOptions<S>& options) {
    if (!options.Valid()) return core::Status::kInvalidArgument;
    options_ = options;
    fade_ = std::exp(-S(1) / options.memory_intervals);
    information_ = S(1) / (options.prior_sigma_s * options.prior_sigma_s);
    offset_s_ = options.initial_offset_s;
    readings_ = 0;
    last_reading_s_ = S(0);
    return core::Status::kOk;
  }

  // One interval u from state prev to next, solved, weighted in the filter by sqrt_information,
  // integrated with applied_offset_s (the estimate's value when its end was integrated). False
  // (nothing changed) when the interval shows no offset (constant rate and force) or a number
  // is not finite.
  bool Observe(const InertialStereoModel<S>& model, const NavState<S>& prev,
               const NavState<S>& next, const ImuPreintegration<S>& u,
               const Mat15<S>& sqrt_information, S applied_offset_s) {
    Mat15<S> j_prev;
    Mat15<S> j_next;
    const Vec15<S> r = sqrt_information * model.ProcessResidual(prev, next, u, &j_prev, &j_next);
    const Vec15<S> g = sqrt_information * model.ProcessTimeShiftJacobian(prev, next, u);
    const S information = g.squaredNorm();
    if (!(information > S(0)) || !std::isfinite(information) || !r.allFinite() ||
        !std::isfinite(applied_offset_s))
      return false;
    const S m = options_.max_offset_s;
    const S reading = std::clamp(-g.dot(r) / information, -m, m);
    information_ = fade_ * information_ + information;
    offset_s_ = std::clamp(applied_offset_s + reading, -m, m);
    last_reading_s_ = reading;
    ++readings_;
    return true;
  }

  S OffsetS() const { return offset_s_; }
  // 1-sigma of the estimate from the information it holds (the readings' stated information;
  // the fading memory keeps it from shrinking without bound).
  S SigmaS() const { return S(1) / std::sqrt(information_); }
  // The last interval's reading d (the offset it still showed).
  S LastReadingS() const { return last_reading_s_; }
  long Readings() const { return readings_; }
  const TimeOffsetOptions<S>& Options() const { return options_; }

 private:
  TimeOffsetOptions<S> options_;
  S fade_ = S(1);
  S information_ = S(0);
  S offset_s_ = S(0);
  S last_reading_s_ = S(0);
  long readings_ = 0;
};

}  // namespace swf::estimator
