// Data-parallel training across processes and machines (`train ssd|rpn|det3d --world-size N`), on
// LibTorch's own distributed engine: c10d's Gloo process group (CPU tensors over TCP), with a
// TCPStore or FileStore for the rendezvous. No torch type crosses this header.
//
// The contract every family's training keeps (docs/scale.md, "Training on several processes"):
//   - every rank reads the same training data and draws the same epoch order; a step's batch of B
//     frames is split into N contiguous slices, rank r training on slice r (B/N frames each);
//   - each family's loss divides by counts over the whole batch (positive anchors, sampled anchors,
//     sampled RoIs, foreground points), all-reduced, so the ranks' losses add up to the
//     single-process loss of the whole batch, and the ranks' gradients are summed (an all-reduce
//     of the flattened gradients in buckets) into that loss's gradient;
//   - batch normalization is synchronized: in training, the batch statistics are those of the whole
//     batch (each layer all-reduces its sums), so the forward pass, the gradients and the running
//     statistics are those of one process with the whole batch;
//   - rank 0 owns the model folder: it alone checks and locks it, writes model.pt, model.json,
//     checkpoint.pt, train_log.csv and run.json, and prints progress; when it resumes it sends the
//     checkpoint's bytes to the other ranks, which need no shared filesystem;
//   - every collective has the group's timeout; a rank that fails (an error, a kill, a lost
//     machine) makes the others stop with an error naming the group, never hang.
#ifndef STEREODET_MODELS_DISTRIBUTED_H_
#define STEREODET_MODELS_DISTRIBUTED_H_

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace stereodet {

struct DistributedOptions {
  int world_size = 1;  // processes training together; 1 = a training of its own
  int rank = 0;        // this process, in [0, world_size); rank 0 writes the model folder
  // Where the ranks meet: "tcp://HOST:PORT" (rank 0 serves a TCPStore on PORT of HOST, the others
  // connect to it; HOST must be rank 0's address as the others reach it) or "file://PATH" (a
  // FileStore: a file every rank can read and write, e.g. on NFS; it must not exist before the
  // run). Required when world_size > 1.
  std::string rendezvous;
  // Seconds the rendezvous and every collective may wait for the other ranks before failing.
  double timeout_s = 300;
  bool Enabled() const { return world_size > 1; }
  // Throws std::invalid_argument: world_size >= 1, rank in range, a rendezvous URL of a known
  // scheme with a port in 1..65535 or a path, timeout_s > 0.
  void Check() const;
};

// `flags` completed from the variables torchrun and `python3 -m torch.distributed.launch` set
// (WORLD_SIZE, RANK, MASTER_ADDR, MASTER_PORT -> tcp://MASTER_ADDR:MASTER_PORT), each only where
// the flags left the field at its default; `environment` is the process's (tests pass their own).
// Throws std::invalid_argument naming a variable that is not a number.
DistributedOptions DistributedOptionsFromEnvironment(
    DistributedOptions flags, const std::map<std::string, std::string>& environment);
// The process's environment variables of the names above.
std::map<std::string, std::string> DistributedEnvironment();

// A connected group of training processes. Every call is a collective: every rank must make the
// same calls in the same order. Throws std::runtime_error naming the group's rank and the cause
// when another rank stopped or a call timed out. Not thread-safe: one thread per process uses it.
class TrainingGroup {
 public:
  // Meets the other ranks at options.rendezvous (waiting up to timeout_s for all of them); null
  // for a world of one (nothing to meet). Throws std::invalid_argument for bad options (Check),
  // std::runtime_error when the group cannot form.
  static std::unique_ptr<TrainingGroup> Connect(const DistributedOptions& options);
  // Whether this build can form a group (LibTorch's Gloo process group; CMake found libgloo-dev's
  // headers). Without it Connect throws std::invalid_argument for a world of more than one.
  static bool Available();
  ~TrainingGroup();
  TrainingGroup(const TrainingGroup&) = delete;
  TrainingGroup& operator=(const TrainingGroup&) = delete;

  int rank() const;
  int world_size() const;
  bool IsRoot() const { return rank() == 0; }
  // "rank 1 of 2" for messages.
  std::string Name() const;

  // Sums `values` over the ranks in place (every rank gets the same sums, in double).
  void AllReduceSum(std::vector<double>& values);
  // Rank 0's `text` on every rank (the other ranks' argument is ignored).
  std::string Broadcast(const std::string& text);
  // Checks that every rank passes the same `value`; throws std::runtime_error naming `what`, the
  // first rank that differs and both values otherwise ("rank 1 has 2990 training frames, rank 0
  // has 3000").
  void CheckSame(const std::string& what, const std::string& value);
  // Waits for every rank.
  void Barrier();

  struct Impl;
  Impl& impl() { return *impl_; }  // the torch side (distributed_internal.h)

 private:
  explicit TrainingGroup(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The slice of a batch of `batch_size` frames that `rank` of `world_size` trains on: frames
// [begin, end) of the batch, contiguous and in rank order, sizes differing by at most one.
struct BatchSlice {
  int begin = 0, end = 0;
};
BatchSlice RankSlice(int batch_size, int rank, int world_size);

// Throws std::invalid_argument unless every step of a training of `num_frames` frames in batches
// of `batch_size` gives each of `world_size` ranks at least one frame: batch_size a multiple of
// world_size and a last batch (num_frames % batch_size, when not 0) of at least world_size frames.
void CheckBatchesSplit(int num_frames, int batch_size, int world_size);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DISTRIBUTED_H_
