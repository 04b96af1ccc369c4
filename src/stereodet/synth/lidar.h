// A Velodyne HDL-64E-like LiDAR ray cast into a synthetic scene.
//
// Beam layout (HDL-64E S2 as in KITTI): 64 lasers in two blocks, the upper 32 spread evenly from
// +2.0 to -8.33 degrees elevation, the lower 32 from -8.83 to -24.9 degrees. One revolution is
// sampled at `azimuth_step_deg` (0.16 degrees by default, 2250 columns: about the 0.08 to 0.17
// degrees of the real sensor at 5 to 10 Hz, and the ~120k points of a KITTI scan). The sensor sits
// where the calibration's Tr_velo_to_cam puts it (KittiLikeCalibration: 1.73 m above the road for
// a camera at 1.65 m), looking along velo x.
#ifndef STEREODET_SYNTH_LIDAR_H_
#define STEREODET_SYNTH_LIDAR_H_

#include <cstdint>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

struct LidarOptions {
  double azimuth_step_deg = 0.16;  // angular step of one revolution, (0, 5]
  double max_range_m = 120.0;      // no return beyond (HDL-64E: 120 m)
  double min_range_m = 2.0;        // returns closer than this are dropped (the ego car's body)
  double range_noise_m = 0.02;     // standard deviation of the range error (HDL-64E: < 2 cm)
  double dropout = 0.02;           // probability that a return is lost at random
  // Dark surfaces (reflectance below 0.05) farther than this return only half the time.
  double dark_dropout_range_m = 40.0;
  double reflectance_noise = 0.02;  // standard deviation added to the intensity

  void Check() const;  // throws std::invalid_argument
};

// Elevation angles of the 64 beams in degrees, upper block first (top to bottom).
std::vector<double> Hdl64ElevationsDeg();

// Casts one revolution and returns the returns in the velo frame (x forward, y left, z up, metres)
// with a reflectance in [0, 1] (multiples of 0.01 like KITTI's), ordered by beam (top first), then
// azimuth (from -180 degrees, counter-clockwise seen from above). Noise and dropouts come from
// `seed` alone.
std::vector<VeloPoint> SimulateLidar(const Scene& scene, const Calibration& calib,
                                     const LidarOptions& options, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_LIDAR_H_
