// Hazard mapping (issue 8): dense stereo + the SWF's pose and covariance + its landmarks fused
// into a local-level elevation grid with per-cell sigma, slope / rock / roughness analysis with
// uncertainty-aware classes, and a stable safe landing site. The one header the flight process
// needs; every buffer is allocated by Configure(), Update() never allocates.
//
// Per Update():
//  1. The rectified pair is reduced by `downsample` (1, 2 or 4; [1 2 1] low-pass) and matched by
//     SGM (dense_stereo.hpp) over a disparity range predicted from the landmarks in view (else
//     from the map, else from ground_z_hint_m).
//  2. Each valid pixel becomes a world point p_w = R p_c + t, p_c = Z (u', v', 1), Z = f B / d.
//     Stereo sigma: sigma_Z = Z^2 sigma_d / (f B) (sigma_d = s disparity_sigma_px (2 -
//     confidence)), projected on the vertical; s >= 1 is this frame's measured disparity noise over
//     the model's, from the SWF landmarks in view (1.4826 x median |SGM - landmark disparity|, less
//     the landmarks' own disparity variance): SGM's error grows where the model does not see it
//     (gross mismatches at 7-20 px of disparity at high altitude). Pixels are averaged per cell
//     into one measurement per frame (neighbouring SGM disparities are correlated, so n counts at
//     most max_independent_pixels).
//  3. The pose error is one error shared by every cell of a frame, not a per-cell noise: before
//     fusing, the map is moved onto the new frame's vertical datum (the inverse-variance mean of
//     frame - map over the cells both hold; Stats().datum_shift_m). Frames fused with different
//     weights per cell would otherwise turn their different pose errors into relief. Frames and
//     landmarks (sigma^2 = their covariance's zz) are then fused per cell by inverse variance of
//     the stereo alone, a frame's cell only when it agrees with the fused cell within
//     outlier_gate_sigmas of their combined sigma (gross SGM mismatches: counted, not fused; a
//     fused cell that rejects outlier_replace_after frames in a row is replaced by the frame's;
//     the datum is the median first, then the mean over the cells within the gate); the elevation
//     sigma adds the newest pose's vertical error at the cell (SWF update vector [rho, phi], p_w =
//     R Exp(phi) p_c + t + rho: J Sigma J^T, J = [e_z^T, -e_z^T R [p_c]x]), the relief sigma does
//     not (the datum is common to its reference window). Landmarks: the SWF publishes its map at
//     every update, and a landmark it keeps is the same point re-estimated, each estimate holding
//     the information of the earlier ones: fusing every publication would count it once per update.
//     An identified landmark (HazardLandmark::id) is held at its newest estimate (replaced, not
//     added, when published again) and enters the cells as an overlay; when the SWF no longer
//     publishes it (marginalized: its estimate is final), that last estimate, moved with the map's
//     datum, is fused for good. At most max_landmarks are held (the size of one published map).
//     Unknown cells stay unknown (NaN). Before fusing, the grid is recentred by whole cells on the
//     frame's nadir (grid_follows_lander): cells that leave are dropped with their state, cells
//     that enter start unknown. The cell size is chosen from altitude (pixels_per_cell working
//     pixels per cell, a power of 2 times min_cell_m) and only ever refined: on refinement the grid
//     is resampled (information per child = parent / 4).
//  4. Analysis over square windows (summed-area tables, O(1) per cell): a plane fit over the
//     lander footprint gives slope and roughness; the metre-scale slope is the central difference
//     of the heights local_slope_baseline_m (1 m) apart along x and y, each end the mean over a
//     local_slope_patch_m square (the height a footpad stands on; see local_slope_patch_m for why
//     not a plane); a quadric over rock_window_radius_m gives each cell's rock height. Sigma of a
//     slope from its cells (their stereo noise, correlated with their neighbours':
//     cell_error_autocorrelation; the footprint plane also from its fit's residuals) and the
//     attitude covariance; sigma of the rock height from the cell's stereo sigma and the fit's
//     (the mean cell variance times the quadric's leverage at the cell).
//     Classes: kRock when the rock height exceeds the rock criterion's decision relief
//     (RockCriterion below); kSlope when either slope exceeds its threshold by confidence_k sigma
//     and its sigma resolves it (sigma <= a third of the threshold; the 1 m slope's patches leave
//     out the cells of declared rocks and their flanks, since a height difference across a rock
//     is the rock's, and the rock is the hazard there); kUncertain when value + k sigma
//     exceeds a slope threshold (where a rock covers a 1 m slope's patch: when it does so at a
//     measured cell within half the baseline, or none is measured there), or, where the criterion
//     does not resolve the threshold rock
//     (where it does, it has decided), when the relief over the threshold rock's footprint leaves
//     such a rock possible (RockCriterion, "Possible"); kSafe otherwise, kUnknown without data.
//  5. Safe site: clearance = Euclidean distance (exact distance transform) to the nearest cell that
//     is not kSafe or to the grid border; candidates need clearance >= footprint radius + margin
//     (site_margin_sigmas x the horizontal position sigma). Score in
//     [0, 1] = (min(clearance / clearance_cap, 1) + 0.5 (1 - sigma / max_rock_height) +
//     target_weight (1 - distance to target / grid half extent)) / (1.5 + target_weight); the
//     previous site is kept while still valid and within site_hysteresis of the best score.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "swf/core/status.hpp"
#include "swf/estimator/geometry.hpp"
#include "swf/frontend/image.hpp"
#include "swf/hazard/dense_stereo.hpp"

namespace swf::hazard {

enum class HazardClass : std::uint8_t { kUnknown = 0, kSafe, kUncertain, kSlope, kRock };

// The rock criterion (docs/hazard.md, "The rock criterion"): when a cell is declared a rock, and
// which rocks a map resolves. One statement, used by the mapper's classification and by the
// hazard-map-vs-truth metric (swf/evaluation/hazard_score.hpp), so the two cannot disagree.
//  - Relief. A cell's rock height is its elevation above the quadric z = a + b x + c y + d x^2 +
//    e x y + f y^2 fitted over +-window_radius_m (window side m = 2 round(window_radius_m / c) + 1
//    cells at cell size c), at the cell. A quadric, not a plane: crater rims and walls curve
//    within 3 m, and their relief above a plane (a crest 0.5 s a above a plane over +-a on a
//    crest of flank slope s, 0.19 s a above the quadric) was read as rocks (the every-2nd-frame
//    campaign's false alarms at 5-10 m, 74-77 % of them on true slopes above 10 deg). A rock of
//    height H and diameter D, modelled as a half spheroid (the simulator's and Golombek's rock
//    shape), shows the noise-free relief r(H, D, c) = (mean of its profile over a c x c cell with
//    a corner at the rock's centre) - (its lift of the quadric at that cell). The corner is the
//    worst alignment with the grid: a rock narrower than a cell is averaged down, and the
//    criterion says so. The lift: the quadric's value at the centre of a whole window weighs the
//    cells by w_i = alpha + beta |x_i|^2 (by symmetry; alpha = 3.5 / m^2 at 5 cm, a plane's
//    1 / m^2), so the rock lifts it by (alpha V + beta (4/15 pi H R^4 + V |d|^2) / c^2) / c^2 (V =
//    2/3 pi R^2 H, R = D / 2, d the cell's centre from the rock's).
//  - Resolution. The map resolves the threshold at sigma (the relief's 1-sigma) when a
//    threshold rock (height h, diameter h / height_to_diameter) stands out of flat ground by the
//    false-alarm and the detection margins together: r_h = r(h, h / height_to_diameter, c) >=
//    (z_fa + z_d) sigma, i.e. sigma <= sigma_max(c) = r_h / (z_fa + z_d): 0.058 / 0.057 / 0.049
//    / 0.015 m at 5 / 10 / 20 / 40 cm cells (r_h 0.276 / 0.268 / 0.232 / 0.073 m: a rock
//    narrower than the cell is averaged down).
//  - Decision. Where the threshold is resolved, kRock when relief > T(sigma) = r_h - z_d sigma.
//    Then T >= z_fa sigma: a cell of flat ground is declared with probability <= 1 - Phi(z_fa) =
//    1e-3 (one-sided Gaussian); a threshold rock's cell exceeds T with probability Phi(z_d) =
//    0.95. Hazard relevance: T sits at a threshold rock's relief less z_d sigma, never at a
//    multiple of sigma alone, so a sharp map does not declare small rocks (at sigma = 0.02 m and
//    5 cm cells a 0.2 m rock is declared with probability 4e-3, a 0.15 m one 2e-7). Where sigma
//    > sigma_max nothing is declared a rock (an exceedance is kUncertain): those are the cells
//    whose sigma is least trustworthy in its tails (SGM mismatches at altitude).
//  - Resolvable. A rock H >= h is resolvable at sigma when its relief clears T by z_d sigma:
//    sigma <= sigma_max and r(H, D, c) - z_d sigma >= T(sigma), i.e. r(H, D, c) >= r_h. The map
//    must detect it with probability >= 0.95.
//  - Possible (where sigma > sigma_max: the map cannot decide, it can only exclude). A rock is a
//    body, not a cell: the threshold rock covers pi (h / height_to_diameter / 2)^2 / c^2 cells
//    (113 at 5 cm) and raises all of them. The question is whether the evidence over its
//    footprint excludes it, not whether one cell's noise does: one cell 2 sigma high among flat
//    neighbours cannot hide a rock that would lift the neighbours too. The test is a box matched
//    filter: the mean relief over the m x m cells centred on the cell (m odd), against the relief
//    r_m = r_box(h, h / height_to_diameter, c, m) that a threshold rock standing with its centre in
//    that cell shows there (the box's centre cell with a corner at the rock's centre, the worst
//    alignment, as r(H, D, c); less the quadric's lift at the box's mean |d|^2). A threshold rock
//    is excluded (at one-sided confidence Phi(k)) when mean + k sigma_m <= r_m; taller rocks of the
//    model's shape show more, so they are excluded too. sigma_m: the cells' stereo relief errors
//    are correlated (shared texture, SGM's correlated matches, frames seen at coarser resolution),
//    modelled as equicorrelated with rho = relief_error_correlation, var = ((1 - rho) sum s_i^2 +
//    rho (sum s_i)^2) / m^4; each cell's quadric error is its window's, shared by the box's nearly
//    identical windows, so it enters fully correlated (its mean). m maximizes the threshold rock's
//    box SNR, r_m m / sqrt(1 + (m^2 - 1) rho): at rho = 0.25, m = 5 / 3 / 1 / 1 at 5 / 10 / 20 / 40
//    cm cells (r_m 0.259 / 0.243 / 0.232 / 0.073 m; sigma_m = 0.53 / 0.58 / 1 / 1 of a uniform
//    stereo sigma). One cell's excess x moves the mean by x / m^2. Where m = 1, or where the box is
//    not all mapped (grid edge, holes), the test is the cell's own: relief + k sigma > r_h.
struct RockCriterionOptions {
  double max_height_m = 0.3;          // h: the rock hazard threshold
  double window_radius_m = 1.5;       // of the relief's reference quadric
  double false_alarm_sigmas = 3.090;  // z_fa: 1 - Phi(z_fa) = 1e-3 per cell
  double detection_sigmas = 1.645;    // z_d: Phi(z_d) = 0.95
  double height_to_diameter = 0.5;    // the rock model's H / D (Golombek & Rapp 1997)
  // rho of the "possible" test: the correlation of the relief errors of cells in one box.
  double relief_error_correlation = 0.25;
};

class RockCriterion {
 public:
  RockCriterion(const RockCriterionOptions& options, double cell_m);
  // r(H, D, c): the relief a noise-free map at this cell size shows for a rock (>= 0).
  double Relief(double height_m, double diameter_m) const;
  // sigma_max: the largest relief sigma at which the map resolves the threshold.
  double ResolvedSigma() const { return resolved_sigma_m_; }
  // T(sigma): a cell is a rock when its relief exceeds this (infinite where sigma > sigma_max).
  double DecisionRelief(double sigma_m) const;
  // A rock the map must detect with probability >= Phi(z_d) at the relief sigma sigma_m.
  bool Resolvable(double height_m, double diameter_m, double sigma_m) const;
  double ThresholdRelief() const { return threshold_relief_m_; }  // r(h, h / (H / D), c)
  // The mean relief of a rock over side_cells x side_cells cells centred on the cell with a corner
  // at its centre (Relief() is side 1).
  double BoxRelief(double height_m, double diameter_m, int side_cells) const;
  // The "possible" test's box: its side m (odd), the threshold rock's relief r_m over it, and the
  // sigma of the box mean from the sums over its cells of the stereo relief sigma, of its square
  // and of the plane's sigma.
  int FootprintCells() const { return footprint_cells_; }
  double FootprintRelief() const { return footprint_relief_m_; }
  double FootprintSigma(double sum_sigma_m, double sum_sigma2_m2, double sum_plane_sigma_m) const;

 private:
  RockCriterionOptions options_;
  double cell_m_ = 0.0;
  double lift_alpha_ = 0.0;  // the reference quadric's centre weights, alpha + beta |x|^2 (cells)
  double lift_beta_ = 0.0;
  double threshold_relief_m_ = 0.0;
  double resolved_sigma_m_ = 0.0;
  int footprint_cells_ = 1;
  double footprint_relief_m_ = 0.0;
};

struct HazardMapperOptions {
  // Full-resolution rectified camera and image size of the pairs Update() receives.
  estimator::StereoCamera<double> camera;
  int image_width = 1024;
  int image_height = 768;
  // Dense stereo.
  int downsample = 2;         // 1, 2 or 4
  int max_disparities = 128;  // at working resolution
  int sgm_paths = 8;
  int sgm_p1 = 8;
  int sgm_p2 = 96;
  float uniqueness = 0.05f;
  float min_confidence = 0.05f;
  double disparity_sigma_px = 0.3;  // at working resolution, confidence 1
  // SGM errors are correlated between neighbouring pixels (autocorrelation ~0.25 at 1 px, ~0.2
  // at 2 px, < 0.07 at 4 px, measured against the renderer's exact disparity): a cell's n pixels
  // count as max(1, n / pixels_per_independent) independent samples, at most
  // max_independent_pixels.
  double pixels_per_independent = 4.0;
  int max_independent_pixels = 64;
  // Fraction of a frame's cell error shared with the other frames over the same cell (the same
  // texture gives the same SGM mismatches from similar viewpoints): fused variance =
  // rho min_k var_k + (1 - rho) / sum_k (1 / var_k) (exact for equicorrelated frames).
  double frame_error_correlation = 0.25;
  // Gross stereo mismatches: a disparity off by many pixels puts a point metres too high, and
  // since sigma_Z grows with Z^2 the too-near point also states a smaller sigma, so
  // inverse-variance fusion trusts it more than the true ones. A frame's cell is fused only when
  // its height agrees with the fused cell's (on the frame's datum) within outlier_gate_sigmas x
  // the combined sigma of the two (Stats().outliers_rejected). A cell that rejects
  // outlier_replace_after consecutive frames is taken to hold the outlier itself (one that
  // entered where the map knew nothing, or knew it only coarsely): its state is replaced by the
  // frame's (Stats().cells_replaced). Gate 0 = off.
  double outlier_gate_sigmas = 5.0;
  int outlier_replace_after = 2;
  // In-flight calibration of the disparity noise against the SWF landmarks in view: the robust
  // spread of (SGM disparity - landmark disparity), less the landmarks' own disparity variance,
  // scales the model sigma up (never down) when at least min_calibration_landmarks match.
  bool calibrate_disparity_sigma = true;
  int min_calibration_landmarks = 8;
  double ground_z_hint_m = 0.0;  // used for the disparity range with no landmark and no map
  // Grid.
  int grid_cells = 256;  // cells per side (capacity and size)
  double min_cell_m = 0.05;
  double max_cell_m = 0.8;
  double pixels_per_cell = 2.0;
  bool target_from_first_pose = true;  // target = nadir of the first frame
  // The grid follows the lander: before each frame is fused it is recentred, by whole cells, on
  // that frame's nadir (the optical axis on the ground). Cells that leave are dropped with their
  // state, cells that enter start unknown. Off, the grid stays centred on the target.
  bool grid_follows_lander = true;
  Eigen::Vector2d target_world_m{0.0, 0.0};
  int max_landmarks = 1024;
  // Hazards (defaults: rocks above 0.3 m, slopes above 10 deg).
  double max_slope_deg = 10.0;
  double max_rock_height_m = RockCriterionOptions{}.max_height_m;
  double footprint_radius_m = 1.5;
  // Slopes are hazards at two scales: over the footprint (the lander's tilt at rest) and over
  // this baseline (a footpad on a metre-scale slope: crater rims and walls that a 3 m plane
  // averages below the threshold; the simulator's truth measures slope over 1 m).
  double local_slope_baseline_m = 1.0;
  // The 1 m slope is (mean height over a patch at +baseline/2 - the same at -baseline/2) /
  // baseline along x and y, the patches this side (rounded to an odd number of cells): the
  // truth's definition (sim/hazard.hpp: the central difference of the heights over the baseline)
  // with each end averaged against the stereo noise. A least-squares plane over the 1 m window
  // measures something else: its slope is the surface's gradient averaged under a parabola that
  // vanishes at the window's ends, so a wall rising in the window's outer third (a crater's inner
  // wall beside its flat floor) reads at about half the height difference it puts across the
  // baseline (40 m campaign runs 6 and 58: true 10.3-11.7 deg, the plane 4.5-8.7 deg on the
  // truth's own heights as on the map's). The patch trades the ends' averaging against the
  // stereo noise (40 m campaign runs 0, 3, 6, 15, 58, last maps, 0.35 / 0.45 / 0.55 m patches:
  // flat cells certified (slope + 2 sigma <= 10 deg) 42 / 53 / 63 %, cells above 10 deg
  // certified 0.3 / 0.7 / 2.3 %; the plane 50 % and 1.6 %; with 0.45 m run 6 chose a site 1.495
  // m from a 10.3 deg cell, with 0.35 m none); at 0.35 m the patch-mean difference of the true
  // heights is within -0.05 deg (median) of the truth's, rms 0.7 deg.
  double local_slope_patch_m = 0.35;
  double rock_window_radius_m = RockCriterionOptions{}.window_radius_m;
  double relief_error_correlation = RockCriterionOptions{}.relief_error_correlation;
  // The map's cell errors are correlated with their neighbours' (the SGM error's own spatial
  // correlation: shared texture, aggregation paths), measured as the autocorrelation of (map -
  // truth) at lags of 1, 2, 4, 8, 16 cells (5 cm cells of the campaigns' last maps: 0.23-0.28,
  // 0.12-0.17, 0.07-0.08, 0.03-0.06, 0.01-0.02; docs/hazard.md, "The 1 m slope's error"),
  // linear between them and zero from 32 cells. A plane fitted as if its cells were independent
  // understates its slope's variance; the slope variance is the fit's times g^T C g / g^T g
  // (g the least-squares gradient weights over the window, C this correlation); the 1 m slope's
  // central difference of two patch means likewise (g: +-1 over the two patches).
  std::array<double, 5> cell_error_autocorrelation{0.255, 0.145, 0.075, 0.045, 0.015};
  double confidence_k = 2.0;
  double min_known_fraction = 0.6;  // of a window, for a plane fit
  // Safe site. Its clearance to every non-safe cell must exceed the footprint radius plus
  // site_margin_sigmas times the horizontal position sigma (the pose covariance's worst horizontal
  // direction): the map's hazards are placed with the navigation's position, so a site a bare
  // footprint radius from a mapped hazard is that close only up to the navigation error.
  double site_margin_sigmas = 2.0;
  double clearance_cap_m = 5.0;
  double target_weight = 0.5;     // weight of closeness to the target in the score
  double site_hysteresis = 0.05;  // score units ([0, 1])
};

// The rock criterion of a mapper's configuration (its threshold and reference window).
RockCriterionOptions RockCriterionOf(const HazardMapperOptions& options);

// A landmark of the SWF (world frame) with its marginal covariance. With an id (>= 0, the SWF's
// landmark id) the landmark is one point of the ground that the SWF keeps re-estimating: it enters
// the map once, as its newest estimate (see HazardMapper, "Landmarks"). Without one (id < 0) it
// is a measurement of its own and is fused at once.
struct HazardLandmark {
  std::int64_t id = -1;
  Eigen::Vector3d position_world_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

struct HazardFrame {
  frontend::GrayView left;  // rectified, image_width x image_height
  frontend::GrayView right;
  estimator::Pose<double> world_T_camera;
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  const HazardLandmark* landmarks = nullptr;
  int num_landmarks = 0;
};

struct SafeSite {
  bool valid = false;
  Eigen::Vector2d position_world_m{0.0, 0.0};
  double elevation_m = 0.0;
  double score = 0.0;
  double clearance_m = 0.0;  // to the nearest non-safe cell or the grid border
  double margin_m = 0.0;     // required beyond the footprint radius (site_margin_sigmas)
  double slope_deg = 0.0;
  double sigma_m = 0.0;
  int stable_updates = 0;  // consecutive updates the site has been kept
};

struct HazardStats {
  std::uint64_t updates = 0;
  int valid_pixels = 0;
  int fused_cells = 0;  // cells measured by this frame
  int landmarks_used = 0;
  int known_cells = 0;
  int safe_cells = 0;
  int rock_cells = 0;
  int slope_cells = 0;
  int uncertain_cells = 0;
  int min_disparity = 0;
  int num_disparities = 0;
  std::uint32_t range_clamped = 0;        // updates whose predicted range exceeded max_disparities
  std::uint32_t landmarks_rejected = 0;   // non-finite, off-grid, repeated id or over max_landmarks
  int landmarks_active = 0;               // identified landmarks held at their newest estimate
  std::uint64_t landmarks_committed = 0;  // identified landmarks fused for good (left the SWF)
  int grid_shift_cells[2] = {0, 0};       // this update's scroll of the grid (FollowLander)
  std::uint64_t cells_dropped = 0;        // known cells that left the grid by scrolling
  int calibration_landmarks = 0;          // landmarks with a valid SGM disparity this update
  double disparity_scale = 1.0;  // measured / model disparity sigma applied this update (>= 1)
  double datum_shift_m = 0.0;    // the map moved onto this frame's vertical datum (FuseStereo)
  int outlier_cells = 0;         // this frame's cells not fused: outside the gate (FuseStereo)
  int replaced_cells = 0;        // this frame's cells that replaced the fused state
  std::uint64_t outliers_rejected = 0;  // all updates: frame cells outside the gate, not fused
  std::uint64_t cells_replaced = 0;     // all updates: fused cells replaced by a frame's
};

class HazardMapper {
 public:
  // Allocates everything. kInvalidArgument for a bad camera, sizes, downsample not 1/2/4,
  // thresholds <= 0, min_cell > max_cell, ...
  core::Status Configure(const HazardMapperOptions& options);
  // Forgets the map (keeps the configuration).
  void Reset();
  // One hazard update. kNotConfigured before Configure(); kInvalidArgument for images of the
  // wrong size, a non-finite pose or covariance, or a landmark array inconsistent with its count.
  // kOk also when no pixel matched (the map is unchanged; Stats().valid_pixels == 0).
  core::Status Update(const HazardFrame& frame);

  // Grid: GridCells() x GridCells(), cell (i, j) centred at world
  // (CornerX() + (i + 0.5) CellM(), CornerY() + (j + 0.5) CellM()); arrays row-major j * n + i.
  int GridCells() const { return n_; }
  double CellM() const { return cell_m_; }
  double CornerX() const { return corner_x_; }
  double CornerY() const { return corner_y_; }
  const float* Elevation() const { return elevation_.data(); }  // NaN = unknown
  const float* Sigma() const { return sigma_.data(); }          // NaN = unknown
  // The 1-sigma of RockHeight(): the cell's pose-free stereo sigma and the plane fit's. The rock
  // criterion decides with it (the pose error common to the quadric's window cancels); NaN where no
  // plane was fitted.
  const float* ReliefSigma() const { return relief_sigma_.data(); }
  // Frames and committed landmarks fused (a landmark still in the SWF counts when it leaves).
  const std::uint16_t* Count() const { return count_.data(); }
  const HazardClass* Classes() const { return class_.data(); }
  const float* SlopeDeg() const { return slope_deg_.data(); }  // footprint plane, NaN unknown
  // Slope over local_slope_baseline_m (1 m; the central difference of two patch means along x
  // and y) and its sigma, degrees; NaN unknown.
  const float* LocalSlopeDeg() const { return local_slope_deg_.data(); }
  const float* LocalSlopeSigmaDeg() const { return local_slope_sigma_deg_.data(); }
  const float* RockHeight() const { return rock_m_.data(); }  // NaN unknown
  // RMS residual of the footprint plane fit (not the largest deviation); NaN unknown.
  const float* Roughness() const { return rough_m_.data(); }
  const float* ClearanceM() const { return clearance_m_.data(); }
  // Cell containing world (x, y); false when outside the grid.
  bool CellOf(double x_m, double y_m, int* i, int* j) const;
  const SafeSite& Site() const { return site_; }
  const Eigen::Vector2d& Target() const { return target_; }
  const HazardStats& Stats() const { return stats_; }
  const SgmMatcher& Stereo() const { return sgm_; }
  const HazardMapperOptions& Options() const { return options_; }

 private:
  void Reduce(const frontend::GrayView& src, std::vector<std::uint8_t>* dst) const;
  void ChooseRange(const HazardFrame& frame, int* min_d, int* num_d);
  void CopyStateToScratch();
  void MaybeRefine(double altitude_m);
  void CalibrateDisparitySigma(const HazardFrame& frame);
  void FuseStereo(const HazardFrame& frame);
  void FollowLander(const Eigen::Vector2d& nadir_world_m);
  void FuseLandmarks(const HazardFrame& frame, double datum_shift_m);
  void CommitLandmark(double x_m, double y_m, double z_m, double var_m2);
  void OverlayActiveLandmarks();
  double FuseCells(const HazardFrame& frame);  // the known cells' mean elevation
  void Analyze(const HazardFrame& frame);
  void SelectSite();
  void DistanceTransform();

  HazardMapperOptions options_;
  bool configured_ = false;
  bool started_ = false;
  SgmMatcher sgm_;
  int work_w_ = 0;
  int work_h_ = 0;
  std::vector<std::uint8_t> left_small_;
  std::vector<std::uint8_t> right_small_;
  std::vector<std::uint8_t> tmp_small_;
  int n_ = 0;
  double cell_m_ = 0.0;
  double corner_x_ = 0.0;
  double corner_y_ = 0.0;
  Eigen::Vector2d target_{0.0, 0.0};
  double predicted_depth_m_ = 1.0;
  double site_margin_m_ = 0.0;
  double disparity_scale_ = 1.0;
  std::vector<double> calib_abs_;    // |SGM - landmark disparity| per matched landmark
  std::vector<double> calib_var_;    // the landmark's own disparity variance
  std::vector<double> calib_model_;  // the model sigma at the landmark's pixel
  // Identified landmarks at their newest estimate (sorted by id; the map's datum), and the
  // incoming set of this update (scratch of the same capacity). They enter Analyze through the
  // overlay (lm_info_, lm_info_z_) and info_ only when they leave the SWF's map.
  struct ActiveLandmark {
    std::int64_t id = 0;
    int order = 0;  // index in the frame's array: the last of repeated ids wins
    double x = 0.0, y = 0.0, z = 0.0, var = 0.0;
  };
  std::vector<ActiveLandmark> active_;
  std::vector<ActiveLandmark> incoming_;
  int num_active_ = 0;
  std::vector<double> lm_info_;
  std::vector<double> lm_info_z_;
  // Fused state per cell.
  std::vector<double> info_;     // sum 1/sigma^2 (stereo, pose-free, + committed landmarks)
  std::vector<double> info_z_;   // sum z/sigma^2
  std::vector<double> min_var_;  // smallest single-frame variance fused (0 = none)
  std::vector<std::uint16_t> count_;
  std::vector<std::uint8_t> rejections_;  // consecutive frames the cell rejected (outlier gate)
  // Per-frame scratch (also used for resampling).
  std::vector<double> f_w_;
  std::vector<double> f_wz_;
  std::vector<double> f_min_var_;  // resampling scratch
  std::vector<std::int32_t> f_n_;
  std::vector<std::uint8_t> f_rejections_;  // resampling scratch
  std::vector<double> datum_diff_;          // frame - map per shared cell (the datum's median)
  // Outputs.
  std::vector<float> elevation_;
  std::vector<float> sigma_;
  std::vector<float> sigma_rel_;
  std::vector<HazardClass> class_;
  std::vector<float> slope_deg_;
  std::vector<float> slope_sigma_deg_;
  std::vector<float> local_slope_deg_;
  std::vector<float> local_slope_sigma_deg_;
  std::vector<float> rock_m_;
  std::vector<float> relief_sigma_;
  std::vector<float> rough_m_;
  std::vector<float> clearance_m_;
  // Summed-area tables, (n+1)^2 each: count, x, y, z, xx, xy, yy, xz, yz, zz, sigma^2.
  std::vector<double> sat_;
  std::vector<std::int32_t> rock_sat_;   // (n+1)^2: declared rocks (row 0 and column 0 stay 0)
  std::vector<std::int32_t> local_sat_;  // 2 (n+1)^2: measured 1 m slopes, of them possible hazards
  // Distance transform scratch.
  std::vector<float> dt_f_;
  std::vector<float> dt_d_;
  std::vector<float> dt_z_;
  std::vector<int> dt_v_;
  SafeSite site_;
  HazardStats stats_;
};

}  // namespace swf::hazard
