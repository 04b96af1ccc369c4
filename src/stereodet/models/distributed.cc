#include "stereodet/models/distributed.h"

// LibTorch's Gloo process group is compiled into libtorch_cpu.so; its header needs the macro that
// LibTorch's own build defines (Debian's cmake config does not) and Gloo's headers (libgloo-dev):
// CMake defines STEREODET_HAVE_GLOO where it finds them. Without them everything here builds
// against c10d's ProcessGroup interface and only Connect refuses a world of more than one.
#if STEREODET_HAVE_GLOO && !defined(USE_C10D_GLOO)
#define USE_C10D_GLOO
#endif
#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <string>
#include <torch/csrc/distributed/c10d/FileStore.hpp>
#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroup.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#if STEREODET_HAVE_GLOO
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#endif
#include <utility>

#include "stereodet/models/distributed_internal.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

constexpr char kTcpScheme[] = "tcp://";
constexpr char kFileScheme[] = "file://";

struct TcpAddress {
  std::string host;
  int port = 0;
};

// "tcp://HOST:PORT" -> {HOST, PORT}; "[::1]:PORT" keeps the address without brackets.
TcpAddress ParseTcpAddress(const std::string& url) {
  const std::string rest = url.substr(std::char_traits<char>::length(kTcpScheme));
  const size_t colon = rest.rfind(':');
  STEREODET_CHECK(colon != std::string::npos && colon > 0)
      << "--rendezvous " << url << ": expected tcp://HOST:PORT";
  TcpAddress address;
  address.host = rest.substr(0, colon);
  if (address.host.size() > 2 && address.host.front() == '[' && address.host.back() == ']') {
    address.host = address.host.substr(1, address.host.size() - 2);
  }
  const std::optional<long long> port = ParseInt(rest.substr(colon + 1));
  STEREODET_CHECK(port && *port >= 1 && *port <= 65535)
      << "--rendezvous " << url << ": the port must be a number in 1..65535";
  address.port = static_cast<int>(*port);
  return address;
}

bool IsLoopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

std::chrono::milliseconds Milliseconds(double seconds) {
  return std::chrono::milliseconds(static_cast<int64_t>(std::ceil(seconds * 1000.0)));
}

}  // namespace

void DistributedOptions::Check() const {
  STEREODET_CHECK(world_size >= 1) << "--world-size must be >= 1, got " << world_size;
  STEREODET_CHECK(rank >= 0 && rank < world_size)
      << "--rank must be in [0, " << world_size << ") for --world-size " << world_size << ", got "
      << rank;
  STEREODET_CHECK(timeout_s > 0 && std::isfinite(timeout_s))
      << "--group-timeout must be > 0 seconds, got " << timeout_s;
  if (!Enabled()) return;
  STEREODET_CHECK(!rendezvous.empty())
      << "--world-size " << world_size
      << " needs --rendezvous tcp://HOST:PORT or file://PATH (or MASTER_ADDR and MASTER_PORT)";
  if (rendezvous.rfind(kTcpScheme, 0) == 0) {
    ParseTcpAddress(rendezvous);
  } else {
    STEREODET_CHECK(rendezvous.rfind(kFileScheme, 0) == 0 &&
                    rendezvous.size() > std::char_traits<char>::length(kFileScheme))
        << "--rendezvous " << rendezvous << ": expected tcp://HOST:PORT or file://PATH";
  }
}

DistributedOptions DistributedOptionsFromEnvironment(
    DistributedOptions flags, const std::map<std::string, std::string>& environment) {
  const DistributedOptions defaults;
  auto number = [&](const char* name) -> std::optional<int> {
    const auto it = environment.find(name);
    if (it == environment.end() || it->second.empty()) return std::nullopt;
    const std::optional<long long> value = ParseInt(it->second);
    STEREODET_CHECK(value && *value >= 0 && *value <= 1 << 20)
        << "environment variable " << name << "=" << it->second << " is not a rank count";
    return static_cast<int>(*value);
  };
  if (flags.world_size == defaults.world_size) {
    if (const std::optional<int> world = number("WORLD_SIZE")) flags.world_size = *world;
  }
  if (flags.rank == defaults.rank) {
    if (const std::optional<int> rank = number("RANK")) flags.rank = *rank;
  }
  if (flags.rendezvous.empty()) {
    const auto addr = environment.find("MASTER_ADDR");
    const auto port = environment.find("MASTER_PORT");
    if (addr != environment.end() && port != environment.end() && !addr->second.empty()) {
      const bool ipv6 = addr->second.find(':') != std::string::npos;
      flags.rendezvous = std::string(kTcpScheme) +
                         (ipv6 ? "[" + addr->second + "]" : addr->second) + ":" + port->second;
    }
  }
  return flags;
}

std::map<std::string, std::string> DistributedEnvironment() {
  std::map<std::string, std::string> environment;
  for (const char* name : {"WORLD_SIZE", "RANK", "MASTER_ADDR", "MASTER_PORT"}) {
    if (const char* value = std::getenv(name)) environment[name] = value;
  }
  return environment;
}

struct TrainingGroup::Impl {
  int rank = 0, world_size = 1;
  double timeout_s = 300;
  c10::intrusive_ptr<c10d::Store> store;
  // Two channels: `group` for everything in program order (batch norms, counts, losses,
  // broadcasts), `gradients` for GradientReducer's buckets, whose place among the batch norms'
  // backward collectives may differ between ranks.
  c10::intrusive_ptr<c10d::ProcessGroup> group, gradients;

  std::string Name() const { return fmt::format("rank {} of {}", rank, world_size); }

  // Runs one collective and waits for it; a failure (a rank gone, a timeout) becomes an error that
  // says where it happened and what it most likely means.
  void Run(const char* what, const std::function<c10::intrusive_ptr<c10d::Work>()>& start) {
    try {
      c10::intrusive_ptr<c10d::Work> work = start();
      work->wait(Milliseconds(timeout_s));
    } catch (const std::exception& e) {
      Fail(what, e);
    }
  }

  // Throws std::runtime_error (STEREODET_THROW_IO); never returns.
  void Fail(const char* what, const std::exception& e) const {
    STEREODET_THROW_IO() << "training group (" << Name() << "): " << what
                         << " failed; another rank has stopped (its own error says why) or "
                            "did not answer within --group-timeout "
                         << timeout_s << " s: " << FirstLine(e.what());
  }

  static std::string FirstLine(const std::string& text) {
    const size_t end = text.find('\n');
    return end == std::string::npos ? text : text.substr(0, end);
  }
};

TrainingGroup::TrainingGroup(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TrainingGroup::~TrainingGroup() = default;

bool TrainingGroup::Available() { return STEREODET_HAVE_GLOO != 0; }

std::unique_ptr<TrainingGroup> TrainingGroup::Connect(const DistributedOptions& options) {
  options.Check();
  if (!options.Enabled()) return nullptr;
  STEREODET_CHECK(Available())
      << "--world-size " << options.world_size
      << ": this build has no Gloo process group (LibTorch's Gloo headers, Debian libgloo-dev, "
         "were not found when it was configured); install them and rebuild, or train with one "
         "process";
  auto impl = std::make_unique<Impl>();
  impl->rank = options.rank;
  impl->world_size = options.world_size;
  impl->timeout_s = options.timeout_s;
  const std::chrono::milliseconds timeout = Milliseconds(options.timeout_s);
  std::string device_host;
  try {
    if (options.rendezvous.rfind(kTcpScheme, 0) == 0) {
      const TcpAddress address = ParseTcpAddress(options.rendezvous);
      c10d::TCPStoreOptions store_options;
      store_options.port = static_cast<uint16_t>(address.port);
      store_options.isServer = options.rank == 0;
      store_options.numWorkers = options.world_size;
      store_options.waitWorkers = true;
      store_options.timeout = timeout;
      impl->store = c10::make_intrusive<c10d::TCPStore>(address.host, store_options);
      // Ranks that meet on the loopback run on one machine: their traffic stays on it.
      if (IsLoopback(address.host)) device_host = "127.0.0.1";
    } else {
      const std::string path =
          options.rendezvous.substr(std::char_traits<char>::length(kFileScheme));
      impl->store = c10::make_intrusive<c10d::FileStore>(path, options.world_size);
      impl->store->setTimeout(timeout);
    }
#if STEREODET_HAVE_GLOO
    auto gloo_options = c10d::ProcessGroupGloo::Options::create(timeout);
    // Without a loopback rendezvous, Gloo binds the interfaces GLOO_SOCKET_IFNAME names ("eth0",
    // or "eth0,eth1"), as PyTorch reads it, else the address of this machine's hostname
    // (docs/scale.md).
    const char* interfaces = std::getenv("GLOO_SOCKET_IFNAME");
    if (!device_host.empty()) {
      gloo_options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForHostname(device_host));
    } else if (interfaces != nullptr && *interfaces != '\0') {
      for (const std::string_view name : Split(interfaces, ',')) {
        if (!name.empty()) {
          gloo_options->devices.push_back(
              c10d::ProcessGroupGloo::createDeviceForInterface(std::string(name)));
        }
      }
    }
    if (gloo_options->devices.empty()) {
      gloo_options->devices.push_back(c10d::ProcessGroupGloo::createDefaultDevice());
    }
    impl->group = c10::make_intrusive<c10d::ProcessGroupGloo>(
        c10::make_intrusive<c10d::PrefixStore>("stereodet", impl->store), options.rank,
        options.world_size, gloo_options);
    impl->gradients = c10::make_intrusive<c10d::ProcessGroupGloo>(
        c10::make_intrusive<c10d::PrefixStore>("stereodet-gradients", impl->store), options.rank,
        options.world_size, gloo_options);
#else
    (void)device_host;
#endif
  } catch (const std::exception& e) {
    STEREODET_THROW_IO() << "training group (rank " << options.rank << " of " << options.world_size
                         << "): cannot meet the other ranks at " << options.rendezvous << " within "
                         << options.timeout_s << " s: " << Impl::FirstLine(e.what());
  }
  return std::unique_ptr<TrainingGroup>(new TrainingGroup(std::move(impl)));
}

int TrainingGroup::rank() const { return impl_->rank; }
int TrainingGroup::world_size() const { return impl_->world_size; }
std::string TrainingGroup::Name() const { return impl_->Name(); }

void TrainingGroup::AllReduceSum(std::vector<double>& values) {
  if (values.empty()) return;
  torch::Tensor t =
      torch::from_blob(values.data(), {static_cast<int64_t>(values.size())}, torch::kFloat64);
  std::vector<torch::Tensor> tensors{t};
  internal::AllReduceSumInPlace(*this, tensors);
}

std::string TrainingGroup::Broadcast(const std::string& text) {
  std::vector<torch::Tensor> size{
      torch::tensor({static_cast<int64_t>(text.size())}, torch::kInt64)};
  internal::BroadcastInPlace(*this, size);
  const int64_t n = size[0].item<int64_t>();
  std::vector<torch::Tensor> bytes{torch::empty({n}, torch::kUInt8)};
  if (IsRoot() && n > 0) std::memcpy(bytes[0].data_ptr(), text.data(), n);
  internal::BroadcastInPlace(*this, bytes);
  return std::string(static_cast<const char*>(bytes[0].data_ptr()), n);
}

void TrainingGroup::CheckSame(const std::string& what, const std::string& value) {
  // Every rank's hash in its own slot, summed: a gather with one collective.
  std::vector<torch::Tensor> hashes{torch::zeros({world_size()}, torch::kInt64)};
  hashes[0][rank()] = static_cast<int64_t>(Fnv1a64(value));
  internal::AllReduceSumInPlace(*this, hashes);
  const torch::Tensor h = hashes[0];
  int differing = -1;
  for (int r = 1; r < world_size() && differing < 0; ++r) {
    if (h[r].item<int64_t>() != h[0].item<int64_t>()) differing = r;
  }
  if (differing < 0) return;
  // Rank `differing`'s value to every rank (a broadcast rooted there), so that all fail alike.
  std::vector<torch::Tensor> size{
      torch::tensor({static_cast<int64_t>(value.size())}, torch::kInt64)};
  impl_->Run("a broadcast", [&] {
    c10d::BroadcastOptions o;
    o.rootRank = differing;
    return impl_->group->broadcast(size, o);
  });
  std::vector<torch::Tensor> bytes{torch::empty({size[0].item<int64_t>()}, torch::kUInt8)};
  if (rank() == differing) std::memcpy(bytes[0].data_ptr(), value.data(), value.size());
  impl_->Run("a broadcast", [&] {
    c10d::BroadcastOptions o;
    o.rootRank = differing;
    return impl_->group->broadcast(bytes, o);
  });
  const std::string other(static_cast<const char*>(bytes[0].data_ptr()), bytes[0].numel());
  const std::string root = Broadcast(value);
  STEREODET_THROW_IO() << "training group: rank " << differing << " has " << what << " " << other
                       << ", rank 0 has " << what << " " << root
                       << "; every rank must train on the same data with the same options";
}

void TrainingGroup::Barrier() {
  impl_->Run("a barrier", [&] { return impl_->group->barrier(); });
}

BatchSlice RankSlice(int batch_size, int rank, int world_size) {
  STEREODET_CHECK(world_size >= 1 && rank >= 0 && rank < world_size && batch_size >= 0)
      << "no slice " << rank << " of " << world_size << " for a batch of " << batch_size;
  const int64_t b = batch_size;
  return {static_cast<int>(b * rank / world_size), static_cast<int>(b * (rank + 1) / world_size)};
}

void CheckBatchesSplit(int num_frames, int batch_size, int world_size) {
  if (world_size <= 1) return;
  STEREODET_CHECK(batch_size % world_size == 0)
      << "--batch-size " << batch_size << " must be a multiple of --world-size " << world_size
      << " (each rank trains on batch-size / world-size frames of every step)";
  const int last = num_frames % batch_size;
  STEREODET_CHECK(last == 0 || last >= world_size)
      << "the last batch of each epoch would hold " << last << " of " << num_frames
      << " frames, fewer than --world-size " << world_size
      << ": a rank would have none (use --max-frames " << num_frames - last
      << " or another --batch-size)";
}

namespace internal {

namespace {

// Gloo reduces CPU tensors: others go through a contiguous CPU copy and back.
template <typename Collective>
void OnCpu(std::vector<torch::Tensor>& tensors, Collective collective) {
  std::vector<torch::Tensor> cpu(tensors.size());
  std::vector<bool> copied(tensors.size(), false);
  for (size_t i = 0; i < tensors.size(); ++i) {
    copied[i] = !tensors[i].device().is_cpu() || !tensors[i].is_contiguous();
    cpu[i] = copied[i] ? tensors[i].to(torch::kCPU).contiguous() : tensors[i];
  }
  collective(cpu);
  for (size_t i = 0; i < tensors.size(); ++i) {
    if (copied[i]) tensors[i].copy_(cpu[i]);
  }
}

// `start` (one collective of the group's program-order channel on one tensor) on each of
// `tensors` in turn, through the CPU: one collective per tensor, as Gloo's collectives of a list
// want equal shapes.
void EachTensor(TrainingGroup& group, std::vector<torch::Tensor>& tensors, const char* what,
                const std::function<c10::intrusive_ptr<c10d::Work>(
                    c10d::ProcessGroup&, std::vector<torch::Tensor>&)>& start) {
  TrainingGroup::Impl& g = group.impl();
  torch::NoGradGuard no_grad;
  OnCpu(tensors, [&](std::vector<torch::Tensor>& cpu) {
    for (torch::Tensor& t : cpu) {
      std::vector<torch::Tensor> one{t};
      g.Run(what, [&] { return start(*g.group, one); });
    }
  });
}

}  // namespace

void AllReduceSumInPlace(TrainingGroup& group, std::vector<torch::Tensor>& tensors) {
  EachTensor(
      group, tensors, "an all-reduce",
      [](c10d::ProcessGroup& pg, std::vector<torch::Tensor>& one) { return pg.allreduce(one); });
}

void BroadcastInPlace(TrainingGroup& group, std::vector<torch::Tensor>& tensors) {
  EachTensor(
      group, tensors, "a broadcast",
      [](c10d::ProcessGroup& pg, std::vector<torch::Tensor>& one) { return pg.broadcast(one); });
}

namespace {

class AllReduceSumFunction : public torch::autograd::Function<AllReduceSumFunction> {
 public:
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& local,
                               TrainingGroup* group) {
    ctx->saved_data["group"] = reinterpret_cast<int64_t>(group);
    std::vector<torch::Tensor> sum{local.clone()};
    AllReduceSumInPlace(*group, sum);
    return sum[0];
  }
  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    auto* group = reinterpret_cast<TrainingGroup*>(ctx->saved_data["group"].toInt());
    std::vector<torch::Tensor> sum{grads[0].clone()};
    AllReduceSumInPlace(*group, sum);
    return {sum[0], torch::Tensor()};
  }
};

}  // namespace

torch::Tensor AllReduceSumWithGradient(TrainingGroup* group, const torch::Tensor& local) {
  if (group == nullptr) return local;
  return AllReduceSumFunction::apply(local, group);
}

double GlobalCount(TrainingGroup* group, double local) {
  if (group == nullptr) return local;
  std::vector<double> value{local};
  group->AllReduceSum(value);
  return value[0];
}

GradientReducer::GradientReducer(TrainingGroup& group, std::vector<torch::Tensor> parameters,
                                 int64_t bucket_bytes)
    : group_(group) {
  for (torch::Tensor& p : parameters) {
    if (p.requires_grad()) parameters_.push_back(p);
  }
  const size_t n = parameters_.size();
  bucket_of_.assign(n, 0);
  offset_of_.assign(n, 0);
  arrived_.assign(n, false);
  // Reverse order: autograd reaches the last layers' parameters first.
  int64_t bytes = 0, elements = 0;
  for (size_t k = n; k-- > 0;) {
    const torch::Tensor& p = parameters_[k];
    const int64_t size = p.numel() * static_cast<int64_t>(p.element_size());
    const bool fits = !buckets_.empty() && bytes + size <= bucket_bytes &&
                      parameters_[buckets_.back().members.front()].scalar_type() == p.scalar_type();
    if (!fits) {
      if (!buckets_.empty()) {
        buckets_.back().flat = torch::zeros(
            {elements}, torch::TensorOptions().dtype(
                            parameters_[buckets_.back().members.front()].scalar_type()));
      }
      buckets_.emplace_back();
      bytes = elements = 0;
    }
    bucket_of_[k] = buckets_.size() - 1;
    offset_of_[k] = static_cast<size_t>(elements);
    buckets_.back().members.push_back(k);
    bytes += size;
    elements += p.numel();
  }
  if (!buckets_.empty()) {
    buckets_.back().flat = torch::zeros(
        {elements},
        torch::TensorOptions().dtype(parameters_[buckets_.back().members.front()].scalar_type()));
  }
  for (size_t k = 0; k < n; ++k) {
    hooks_.push_back(
        parameters_[k].register_hook([this, k](const torch::Tensor& grad) { Ready(k, grad); }));
  }
}

GradientReducer::~GradientReducer() {
  for (size_t k = 0; k < hooks_.size(); ++k) parameters_[k].remove_hook(hooks_[k]);
}

void GradientReducer::Ready(size_t k, const torch::Tensor& grad) {
  if (!active_ || arrived_[k]) return;
  torch::NoGradGuard no_grad;
  Bucket& bucket = buckets_[bucket_of_[k]];
  bucket.flat.narrow(0, static_cast<int64_t>(offset_of_[k]), parameters_[k].numel())
      .copy_(grad.reshape({-1}));
  arrived_[k] = true;
  ++bucket.ready;
  SendReadyBuckets();
}

void GradientReducer::SendReadyBuckets() {
  TrainingGroup::Impl& impl = group_.impl();
  while (next_to_send_ < buckets_.size() &&
         buckets_[next_to_send_].ready ==
             static_cast<int>(buckets_[next_to_send_].members.size())) {
    Bucket& bucket = buckets_[next_to_send_++];
    std::vector<torch::Tensor> one{bucket.flat};
    c10::intrusive_ptr<c10d::Work> work;
    try {
      work = impl.gradients->allreduce(one);
    } catch (const std::exception& e) {
      impl.Fail("the gradient all-reduce", e);
    }
    const double timeout_s = impl.timeout_s;
    waits_.push_back([work, timeout_s, &impl] {
      try {
        work->wait(Milliseconds(timeout_s));
      } catch (const std::exception& e) {
        impl.Fail("the gradient all-reduce", e);
      }
    });
  }
}

void GradientReducer::Backward(const torch::Tensor& loss) {
  std::fill(arrived_.begin(), arrived_.end(), false);
  for (Bucket& b : buckets_) b.ready = 0;
  next_to_send_ = 0;
  waits_.clear();
  active_ = true;
  try {
    loss.backward();
  } catch (...) {
    active_ = false;
    throw;
  }
  active_ = false;
  torch::NoGradGuard no_grad;
  // What this rank's graph did not reach adds zeros; then the rest is sent, in bucket order.
  for (size_t k = 0; k < parameters_.size(); ++k) {
    if (arrived_[k]) continue;
    Bucket& bucket = buckets_[bucket_of_[k]];
    bucket.flat.narrow(0, static_cast<int64_t>(offset_of_[k]), parameters_[k].numel()).zero_();
    ++bucket.ready;
  }
  SendReadyBuckets();
  for (const std::function<void()>& wait : waits_) wait();
  for (size_t k = 0; k < parameters_.size(); ++k) {
    torch::Tensor& p = parameters_[k];
    if (!p.grad().defined()) p.mutable_grad() = torch::zeros_like(p);
    p.mutable_grad().copy_(buckets_[bucket_of_[k]]
                               .flat.narrow(0, static_cast<int64_t>(offset_of_[k]), p.numel())
                               .view_as(p));
  }
}

std::unique_ptr<GradientReducer> JoinGroup(TrainingGroup* group, torch::nn::Module& module) {
  AttachGroup(module, group);
  if (group == nullptr) return nullptr;
  BroadcastModuleState(*group, module);
  return std::make_unique<GradientReducer>(*group, module.parameters());
}

void BroadcastModuleState(TrainingGroup& group, torch::nn::Module& module) {
  std::vector<torch::Tensor> state;
  for (const auto& p : module.named_parameters()) state.push_back(p.value());
  for (const auto& b : module.named_buffers()) state.push_back(b.value());
  BroadcastInPlace(group, state);
}

torch::Tensor SynchronizedBatchNorm(const torch::Tensor& x, const torch::Tensor& weight,
                                    const torch::Tensor& bias, torch::Tensor& running_mean,
                                    torch::Tensor& running_var, torch::Tensor& num_batches_tracked,
                                    const c10::optional<double>& momentum, double eps,
                                    TrainingGroup& group) {
  STEREODET_CHECK(x.dim() >= 2) << "batch norm of a " << x.dim() << "-d input";
  const int64_t channels = x.size(1);
  std::vector<int64_t> dims{0};
  for (int64_t d = 2; d < x.dim(); ++d) dims.push_back(d);
  std::vector<int64_t> shape(x.dim(), 1);
  shape[1] = channels;
  // Each rank's mean and variance by LibTorch's fused reduction in x's type, turned into sums in
  // double (n mean, n (var + mean^2)) for the all-reduce: the whole batch's E[x^2] - E[x]^2 is
  // then taken in double, and the activations are never copied to double.
  const int64_t local_count = channels > 0 ? x.numel() / channels : 0;
  torch::Tensor local_sums;
  if (local_count > 0) {
    const auto [local_var, local_mean] = torch::var_mean(x, dims, /*unbiased=*/false);
    const torch::Tensor m = local_mean.to(torch::kFloat64);
    const double n = static_cast<double>(local_count);
    local_sums = torch::cat({m * n, (local_var.to(torch::kFloat64) + m * m) * n});
  } else {
    // Zeros that still hang on x's graph: every rank's backward must reach the all-reduce below,
    // or the ranks' collectives would pair up wrongly.
    const torch::Tensor zero = x.sum(dims).to(torch::kFloat64);
    local_sums = torch::cat({zero, zero});
  }
  const torch::Tensor local = torch::cat(
      {local_sums, torch::full({1}, static_cast<double>(local_count),
                               x.options().dtype(torch::kFloat64).requires_grad(false))});
  const torch::Tensor total = AllReduceSumWithGradient(&group, local);
  const double count = total[2 * channels].item<double>();
  STEREODET_CHECK(count > 1) << "batch norm in training needs more than one value per channel "
                                "over the group's batch, got "
                             << count;
  const torch::Tensor mean = total.narrow(0, 0, channels) / count;
  const torch::Tensor var =
      (total.narrow(0, channels, channels) / count - mean * mean).clamp_min(0);
  // y = (x - mean) scale + bias, scale = weight / sqrt(var + eps): two passes over the
  // activations (and their backward), the per-channel arithmetic in double. The difference first,
  // as LibTorch's kernel, so a mean far from zero costs no digits.
  torch::Tensor scale = torch::rsqrt(var + eps);
  if (weight.defined()) scale = scale * weight.to(torch::kFloat64);
  const torch::ScalarType type = x.scalar_type();
  const torch::Tensor centred = x - mean.to(type).view(shape);
  const torch::Tensor y = bias.defined() ? torch::addcmul(bias.to(type).view(shape), centred,
                                                          scale.to(type).view(shape))
                                         : centred * scale.to(type).view(shape);
  if (running_mean.defined()) {
    torch::NoGradGuard no_grad;
    double factor = momentum.value_or(0.0);
    if (num_batches_tracked.defined()) {
      num_batches_tracked += 1;
      if (!momentum) factor = 1.0 / num_batches_tracked.item<double>();
    }
    // LibTorch's update: running = (1 - factor) * running + factor * batch (the variance unbiased).
    running_mean.mul_(1 - factor).add_(mean.detach().to(running_mean.scalar_type()) * factor);
    running_var.mul_(1 - factor)
        .add_((var.detach() * (count / (count - 1))).to(running_var.scalar_type()) * factor);
  }
  return y;
}

template <int D>
BatchNormSyncImpl<D>::BatchNormSyncImpl(int64_t features) : num_features(features) {
  reset();
}

template <int D>
void BatchNormSyncImpl<D>::reset() {
  // LibTorch's BatchNormImplBase::reset and reset_parameters, in their order.
  weight = this->register_parameter("weight", torch::empty({num_features}));
  bias = this->register_parameter("bias", torch::empty({num_features}));
  running_mean = this->register_buffer("running_mean", torch::zeros({num_features}));
  running_var = this->register_buffer("running_var", torch::ones({num_features}));
  num_batches_tracked =
      this->register_buffer("num_batches_tracked", torch::tensor(0, torch::dtype(torch::kLong)));
  torch::NoGradGuard no_grad;
  running_mean.zero_();
  running_var.fill_(1);
  num_batches_tracked.zero_();
  torch::nn::init::ones_(weight);
  torch::nn::init::zeros_(bias);
}

template <int D>
torch::Tensor BatchNormSyncImpl<D>::forward(const torch::Tensor& x) {
  if constexpr (D == 1) {
    TORCH_CHECK(x.dim() == 2 || x.dim() == 3, "expected 2D or 3D input (got ", x.dim(), "D input)");
  } else {
    TORCH_CHECK(x.dim() == 4, "expected 4D input (got ", x.dim(), "D input)");
  }
  if (group_ != nullptr && this->is_training()) {
    return SynchronizedBatchNorm(x, weight, bias, running_mean, running_var, num_batches_tracked,
                                 momentum, eps, *group_);
  }
  // LibTorch's BatchNormImplBase::forward with momentum 0.1 and running statistics tracked.
  if (this->is_training()) num_batches_tracked += 1;
  return torch::nn::functional::detail::batch_norm(x, running_mean, running_var, weight, bias,
                                                   this->is_training(), momentum, eps);
}

template <int D>
void BatchNormSyncImpl<D>::pretty_print(std::ostream& stream) const {
  stream << "stereodet::BatchNorm" << D << "dSync(" << num_features << ", eps=" << eps
         << ", momentum=" << momentum << ")";
}

template class BatchNormSyncImpl<1>;
template class BatchNormSyncImpl<2>;

int AttachGroup(torch::nn::Module& module, TrainingGroup* group) {
  int attached = 0;
  for (const std::shared_ptr<torch::nn::Module>& m : module.modules(/*include_self=*/true)) {
    if (auto* bn1 = dynamic_cast<BatchNorm1dSyncImpl*>(m.get())) {
      bn1->set_group(group);
      ++attached;
    } else if (auto* bn2 = dynamic_cast<BatchNorm2dSyncImpl*>(m.get())) {
      bn2->set_group(group);
      ++attached;
    } else if (dynamic_cast<torch::nn::BatchNorm1dImpl*>(m.get()) != nullptr ||
               dynamic_cast<torch::nn::BatchNorm2dImpl*>(m.get()) != nullptr) {
      throw std::logic_error("a plain BatchNorm in " + module.name() +
                             ": its statistics would be one rank's (use BatchNorm1dSync / "
                             "BatchNorm2dSync, distributed_internal.h)");
    }
  }
  return attached;
}

}  // namespace internal

}  // namespace stereodet
