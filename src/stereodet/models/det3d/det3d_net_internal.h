// Tensor pieces of the 3D detector's network, exposed for its tests (det3d_net_test.cc) only.
// Includes LibTorch.
#ifndef STEREODET_MODELS_DET3D_DET3D_NET_INTERNAL_H_
#define STEREODET_MODELS_DET3D_DET3D_NET_INTERNAL_H_

#include <torch/torch.h>

#include "stereodet/models/det3d/det3d_targets.h"

namespace stereodet::internal {

// The pillar scatter: per point features [N, C] (>= 0, after the ReLU), per point slot (pillar *
// max_points + rank in its pillar, -1 = dropped) and per pillar its flat cell (b * rows * cols +
// cell) -> canvas [batch, C, rows, cols]: each pillar's cell holds the max over its kept points,
// every other cell 0.
torch::Tensor ScatterPillars(const torch::Tensor& point_features, const torch::Tensor& point_slot,
                             const torch::Tensor& pillar_cell, int64_t num_pillars, int max_points,
                             int64_t batch, int rows, int cols);

// PSWarp's sampling grid: boxes [B, A, 7] (x, y, z, l, w, h, yaw), part offsets part_u, part_v [P]
// (fractions of l and w, PartSamplingPoints' order) -> grid_sample coordinates [B, A, P, 2]
// (NormalizedBevCoordinates of each part centre).
torch::Tensor PartSamplingGrid(const torch::Tensor& boxes, const torch::Tensor& part_u,
                               const torch::Tensor& part_v, const BevGridOptions& grid);

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_DET3D_DET3D_NET_INTERNAL_H_
