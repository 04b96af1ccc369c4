// The torch side of data-parallel training (distributed.h): collectives on tensors, the gradient
// all-reduce, an all-reduce that autograd differentiates, and the synchronized batch norm. For
// the models module and its tests only.
#ifndef STEREODET_MODELS_DISTRIBUTED_INTERNAL_H_
#define STEREODET_MODELS_DISTRIBUTED_INTERNAL_H_

#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "stereodet/models/distributed.h"

namespace stereodet::internal {

// Sums `tensors` over the group in place (each on any device; moved through the CPU for Gloo).
void AllReduceSumInPlace(TrainingGroup& group, std::vector<torch::Tensor>& tensors);
// Rank 0's values of `tensors` into every rank's, in place.
void BroadcastInPlace(TrainingGroup& group, std::vector<torch::Tensor>& tensors);

// The sum of `local` over the group, as a tensor autograd differentiates: the gradient that reaches
// each rank's `local` is the sum of every rank's gradient of the result (each rank's loss depends
// on every rank's input through the sum). `local` itself when `group` is null.
torch::Tensor AllReduceSumWithGradient(TrainingGroup* group, const torch::Tensor& local);

// A count of the whole batch: `local` summed over the group, or `local` when `group` is null.
double GlobalCount(TrainingGroup* group, double local);

// Rank 0's parameters and buffers into every rank's `module` (in named order): a new training
// starts every rank from the same weights whatever their initializations drew.
void BroadcastModuleState(TrainingGroup& group, torch::nn::Module& module);

// Batch norm over the whole group's batch (training mode): the mean and variance of every channel
// are those of all ranks' inputs together (sums all-reduced, in double), the gradients flow through
// the all-reduce, and the running statistics move as LibTorch's BatchNorm moves them with the
// whole batch (momentum, the unbiased variance, num_batches_tracked). `x` is [N, C, ...]; the
// group's batch must hold more than one value per channel.
torch::Tensor SynchronizedBatchNorm(const torch::Tensor& x, const torch::Tensor& weight,
                                    const torch::Tensor& bias, torch::Tensor& running_mean,
                                    torch::Tensor& running_var, torch::Tensor& num_batches_tracked,
                                    const c10::optional<double>& momentum, double eps,
                                    TrainingGroup& group);

// LibTorch's BatchNorm1d (D = 1: input [N, C] or [N, C, L]) and BatchNorm2d (D = 2: [N, C, H, W])
// with their defaults (eps 1e-5, momentum 0.1, affine, running statistics), synchronized over
// `group` while training when a group is attached (AttachGroup). The same parameters and buffers
// in the same order and with the same names (weight, bias, running_mean, running_var,
// num_batches_tracked), so model.pt and checkpoints are those of LibTorch's modules; without a
// group, or in evaluation, LibTorch's own batch_norm call with the same arguments, bit for bit.
// (Not a subclass of LibTorch's: Debian's libtorch does not export the base's pretty_print.)
template <int D>
class BatchNormSyncImpl : public torch::nn::Cloneable<BatchNormSyncImpl<D>> {
 public:
  explicit BatchNormSyncImpl(int64_t num_features);
  void reset() override;
  torch::Tensor forward(const torch::Tensor& x);
  void pretty_print(std::ostream& stream) const override;
  void set_group(TrainingGroup* group) { group_ = group; }

  int64_t num_features = 0;
  double eps = 1e-5;
  double momentum = 0.1;
  torch::Tensor weight, bias, running_mean, running_var, num_batches_tracked;

 private:
  TrainingGroup* group_ = nullptr;
};
using BatchNorm1dSyncImpl = BatchNormSyncImpl<1>;
using BatchNorm2dSyncImpl = BatchNormSyncImpl<2>;
TORCH_MODULE_IMPL(BatchNorm1dSync, BatchNorm1dSyncImpl);
TORCH_MODULE_IMPL(BatchNorm2dSync, BatchNorm2dSyncImpl);

// Attaches `group` (or detaches, with null) to every synchronized batch norm in `module`; returns
// how many. Throws std::logic_error for a plain BatchNorm1d/2d in `module`: its statistics would be
// one rank's, silently.
int AttachGroup(torch::nn::Module& module, TrainingGroup* group);

// The gradients of `parameters` summed over the group, the all-reduces overlapped with the
// backward pass: a hook on every parameter copies its gradient into its bucket as autograd makes
// it, and each bucket (parameters in reverse order, at most `bucket_bytes`, so the first bucket
// fills first) is sent as soon as it is full and every bucket before it was sent; Backward()
// sends the rest (a parameter this rank's graph did not reach counts as zeros), waits, and writes
// the sums into the parameters' gradients. The buckets travel on the group's own gradient
// channel, in bucket order on every rank, apart from the batch norms' collectives, whose place
// among them may differ between ranks. The parameters must outlive the reducer; one backward at a
// time.
class GradientReducer {
 public:
  GradientReducer(TrainingGroup& group, std::vector<torch::Tensor> parameters,
                  int64_t bucket_bytes = 16 << 20);
  ~GradientReducer();
  GradientReducer(const GradientReducer&) = delete;
  GradientReducer& operator=(const GradientReducer&) = delete;

  // loss.backward() with the all-reduces overlapped; afterwards every parameter's gradient is the
  // group's sum.
  void Backward(const torch::Tensor& loss);
  int num_buckets() const { return static_cast<int>(buckets_.size()); }

 private:
  struct Bucket {
    std::vector<size_t> members;  // indices into parameters_
    torch::Tensor flat;           // float/double CPU, the members' gradients end to end
    int ready = 0;
  };
  void Ready(size_t parameter, const torch::Tensor& grad);
  void SendReadyBuckets();

  TrainingGroup& group_;
  std::vector<torch::Tensor> parameters_;
  std::vector<size_t> bucket_of_, offset_of_;  // per parameter
  std::vector<bool> arrived_;                  // per parameter, this backward
  std::vector<Bucket> buckets_;
  size_t next_to_send_ = 0;
  bool active_ = false;
  std::vector<unsigned> hooks_;
  std::vector<std::function<void()>> waits_;  // one per sent bucket, in order
};

// What each family's trainer's SetGroup does to its network: `module` trains as one rank of
// `group` from now on (null: alone): its batch norms synchronized over the group (AttachGroup), its
// weights rank 0's (BroadcastModuleState). Returns the reducer of its gradients, null without a
// group.
std::unique_ptr<GradientReducer> JoinGroup(TrainingGroup* group, torch::nn::Module& module);

// What each family's trainer calls instead of loss.backward(): with a reducer, the backward with
// the group's gradient sums overlapped (GradientReducer::Backward); without, loss.backward().
inline void Backward(const torch::Tensor& loss, GradientReducer* reducer) {
  if (reducer != nullptr) {
    reducer->Backward(loss);
  } else {
    loss.backward();
  }
}

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_DISTRIBUTED_INTERNAL_H_
