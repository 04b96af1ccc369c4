#include "stereodet/models/distributed.h"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <exception>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "stereodet/models/distributed_internal.h"
#include "stereodet/util/check.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

// A build without Gloo's headers forms no group (TrainingGroup::Available): its tests skip.
#define SKIP_WITHOUT_GLOO()                                               \
  if (!TrainingGroup::Available()) {                                      \
    GTEST_SKIP() << "this build has no Gloo process group (libgloo-dev)"; \
  }

// Runs `body` on `world` ranks, one thread each, meeting at `rendezvous`; returns each rank's
// exception (null where it finished).
std::vector<std::exception_ptr> RunRanks(int world, const std::string& rendezvous,
                                         const std::function<void(TrainingGroup&)>& body,
                                         double timeout_s = 30) {
  std::vector<std::exception_ptr> errors(world);
  std::vector<std::thread> threads;
  for (int r = 0; r < world; ++r) {
    threads.emplace_back([&, r] {
      try {
        DistributedOptions options;
        options.world_size = world;
        options.rank = r;
        options.rendezvous = rendezvous;
        options.timeout_s = timeout_s;
        const std::unique_ptr<TrainingGroup> group = TrainingGroup::Connect(options);
        body(*group);
      } catch (...) {
        errors[r] = std::current_exception();
      }
    });
  }
  for (std::thread& t : threads) t.join();
  return errors;
}

std::string Message(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

void ExpectNoErrors(const std::vector<std::exception_ptr>& errors) {
  for (size_t r = 0; r < errors.size(); ++r) {
    EXPECT_FALSE(errors[r]) << "rank " << r << ": " << (errors[r] ? Message(errors[r]) : "");
  }
}

// A free TCP port of the loopback (bound, read, released).
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  close(fd);
  return ntohs(address.sin_port);
}

TEST(DistributedTest, RankSlicesCoverEveryBatchOnceInOrder) {
  for (int batch = 1; batch <= 17; ++batch) {
    for (int world = 1; world <= batch; ++world) {
      int next = 0;
      for (int r = 0; r < world; ++r) {
        const BatchSlice s = RankSlice(batch, r, world);
        EXPECT_EQ(s.begin, next) << batch << " " << world << " " << r;
        const int size = s.end - s.begin;
        EXPECT_TRUE(size == batch / world || size == batch / world + 1) << size;
        next = s.end;
      }
      EXPECT_EQ(next, batch);
    }
  }
  EXPECT_EQ(RankSlice(8, 1, 2).begin, 4);
  EXPECT_EQ(RankSlice(5, 1, 2).begin, 2);  // 2 + 3
  EXPECT_THROW(RankSlice(4, 2, 2), std::invalid_argument);
}

TEST(DistributedTest, BatchesMustGiveEveryRankFrames) {
  EXPECT_NO_THROW(CheckBatchesSplit(10, 3, 1));
  EXPECT_NO_THROW(CheckBatchesSplit(12, 4, 2));
  EXPECT_NO_THROW(CheckBatchesSplit(14, 4, 2));  // last batch of 2
  try {
    CheckBatchesSplit(13, 4, 2);  // last batch of 1
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("--max-frames 12"));
  }
  EXPECT_THROW(CheckBatchesSplit(12, 3, 2), std::invalid_argument);
}

TEST(DistributedTest, OptionsAreCheckedAndTakenFromTheEnvironment) {
  DistributedOptions o;
  EXPECT_NO_THROW(o.Check());
  EXPECT_EQ(TrainingGroup::Connect(o), nullptr);  // a world of one meets nobody
  o.world_size = 2;
  EXPECT_THROW(o.Check(), std::invalid_argument);  // no rendezvous
  o.rendezvous = "tcp://host:0";
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.rendezvous = "udp://host:80";
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.rendezvous = "tcp://10.0.0.1:29500";
  EXPECT_NO_THROW(o.Check());
  o.rank = 2;
  EXPECT_THROW(o.Check(), std::invalid_argument);

  const DistributedOptions env = DistributedOptionsFromEnvironment(
      {}, {{"WORLD_SIZE", "4"}, {"RANK", "3"}, {"MASTER_ADDR", "node1"}, {"MASTER_PORT", "29400"}});
  EXPECT_EQ(env.world_size, 4);
  EXPECT_EQ(env.rank, 3);
  EXPECT_EQ(env.rendezvous, "tcp://node1:29400");
  DistributedOptions flags;
  flags.world_size = 2;
  flags.rendezvous = "file:///shared/rdv";
  const DistributedOptions kept =
      DistributedOptionsFromEnvironment(flags, {{"WORLD_SIZE", "4"}, {"MASTER_ADDR", "a"}});
  EXPECT_EQ(kept.world_size, 2);
  EXPECT_EQ(kept.rendezvous, "file:///shared/rdv");
  EXPECT_EQ(DistributedOptionsFromEnvironment({}, {{"MASTER_ADDR", "::1"}, {"MASTER_PORT", "5"}})
                .rendezvous,
            "tcp://[::1]:5");
  EXPECT_THROW(DistributedOptionsFromEnvironment({}, {{"RANK", "one"}}), std::invalid_argument);
}

TEST(DistributedTest, SumsBroadcastsAndAgreementOverThreeRanks) {
  SKIP_WITHOUT_GLOO();
  const TestTempDir dir("distributed");
  const auto errors =
      RunRanks(3, "file://" + (dir.path() / "store").string(), [](TrainingGroup& g) {
        std::vector<double> v{static_cast<double>(g.rank()), 1.5};
        g.AllReduceSum(v);
        EXPECT_EQ(v, (std::vector<double>{3.0, 4.5}));
        EXPECT_EQ(g.Broadcast("from rank " + std::to_string(g.rank())), "from rank 0");
        EXPECT_EQ(g.Broadcast(""), "");
        g.CheckSame("the frames", "3000 frames");
        g.Barrier();
        try {
          g.CheckSame("frames", g.rank() == 2 ? "2990" : "3000");
          ADD_FAILURE() << "rank " << g.rank() << " did not see the difference";
        } catch (const std::runtime_error& e) {
          EXPECT_THAT(e.what(), HasSubstr("rank 2 has frames 2990, rank 0 has frames 3000"));
        }
      });
  ExpectNoErrors(errors);
}

TEST(DistributedTest, TcpRendezvousOnTheLoopback) {
  SKIP_WITHOUT_GLOO();
  const std::string url = "tcp://127.0.0.1:" + std::to_string(FreePort());
  const auto errors = RunRanks(2, url, [](TrainingGroup& g) {
    std::vector<double> v{1.0};
    g.AllReduceSum(v);
    EXPECT_EQ(v[0], 2.0);
    EXPECT_EQ(g.Name(), "rank " + std::to_string(g.rank()) + " of 2");
  });
  ExpectNoErrors(errors);
}

TEST(DistributedTest, TheInterfacesOfGlooSocketIfnameAreBound) {
  SKIP_WITHOUT_GLOO();
  const TestTempDir dir("distributed");
  setenv("GLOO_SOCKET_IFNAME", "lo", 1);
  auto errors = RunRanks(2, "file://" + (dir.path() / "store").string(), [](TrainingGroup& g) {
    std::vector<double> v{1.0};
    g.AllReduceSum(v);
    EXPECT_EQ(v[0], 2.0);
  });
  ExpectNoErrors(errors);
  // An interface this machine lacks: the group cannot form, and says where it was to meet.
  setenv("GLOO_SOCKET_IFNAME", "no_such_interface0", 1);
  DistributedOptions o;
  o.world_size = 2;
  o.rendezvous = "file://" + (dir.path() / "store2").string();
  o.timeout_s = 2;
  try {
    TrainingGroup::Connect(o);
    ADD_FAILURE() << "connected through an interface that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot meet the other ranks at file://"));
  }
  unsetenv("GLOO_SOCKET_IFNAME");
}

TEST(DistributedTest, ARankThatStopsStopsTheOthersWithAnError) {
  SKIP_WITHOUT_GLOO();
  const TestTempDir dir("distributed");
  const auto errors = RunRanks(
      2, "file://" + (dir.path() / "store").string(),
      [](TrainingGroup& g) {
        std::vector<double> v{1.0};
        g.AllReduceSum(v);
        if (g.rank() == 1) throw std::runtime_error("rank 1 failed on its own");
        g.AllReduceSum(v);  // rank 1 never comes
      },
      /*timeout_s=*/5);
  ASSERT_TRUE(errors[0] && errors[1]);
  EXPECT_THAT(Message(errors[0]), HasSubstr("training group (rank 0 of 2): an all-reduce failed"));
  EXPECT_THAT(Message(errors[1]), HasSubstr("rank 1 failed on its own"));
}

// What one process computes with the whole batch `x` and upstream gradient `w`: the output, the
// input's gradient and the affine parameters' gradients, and the running statistics after.
struct BatchNormRun {
  torch::Tensor y, dx, dweight, dbias, running_mean, running_var, tracked;
};

template <typename Module>
BatchNormRun RunBatchNorm(Module& bn, const torch::Tensor& x, const torch::Tensor& w,
                          internal::GradientReducer* reducer = nullptr) {
  const torch::Tensor input = x.clone().requires_grad_(true);
  const torch::Tensor y = bn->forward(input);
  internal::Backward((y * w).sum(), reducer);
  return {y.detach(),
          input.grad(),
          bn->weight.grad().clone(),
          bn->bias.grad().clone(),
          bn->running_mean.clone(),
          bn->running_var.clone(),
          bn->num_batches_tracked.clone()};
}

template <typename Plain, typename Sync>
void ExpectSynchronizedEqualsWholeBatch(const torch::Tensor& x, int split) {
  torch::manual_seed(3);
  const torch::Tensor w = torch::randn(x.sizes(), torch::kFloat64).to(torch::kFloat32);
  Plain plain(x.size(1));
  {
    torch::NoGradGuard no_grad;
    plain->weight.uniform_(0.5, 1.5);
    plain->bias.uniform_(-0.5, 0.5);
  }
  plain->train();
  const BatchNormRun whole = RunBatchNorm(plain, x, w);

  const TestTempDir dir("distributed");
  std::vector<BatchNormRun> ranks(2);
  const auto errors =
      RunRanks(2, "file://" + (dir.path() / "store").string(), [&](TrainingGroup& g) {
        Sync bn(x.size(1));
        {
          torch::NoGradGuard no_grad;
          bn->weight.copy_(plain->weight);
          bn->bias.copy_(plain->bias);
        }
        bn->train();
        EXPECT_EQ(internal::AttachGroup(*bn, &g), 1);
        const int64_t begin = g.rank() == 0 ? 0 : split;
        const int64_t end = g.rank() == 0 ? split : x.size(0);
        internal::GradientReducer reducer(g, bn->parameters());
        ranks[g.rank()] =
            RunBatchNorm(bn, x.slice(0, begin, end), w.slice(0, begin, end), &reducer);
      });
  ExpectNoErrors(errors);
  const torch::Tensor y = torch::cat({ranks[0].y, ranks[1].y});
  const torch::Tensor dx = torch::cat({ranks[0].dx, ranks[1].dx});
  EXPECT_TRUE(torch::allclose(y, whole.y, 1e-5, 1e-5));
  EXPECT_TRUE(torch::allclose(dx, whole.dx, 1e-4, 1e-5)) << (dx - whole.dx).abs().max();
  for (const BatchNormRun& r : ranks) {
    EXPECT_TRUE(torch::allclose(r.dweight, whole.dweight, 1e-4, 1e-5));
    EXPECT_TRUE(torch::allclose(r.dbias, whole.dbias, 1e-4, 1e-5));
    EXPECT_TRUE(torch::allclose(r.running_mean, whole.running_mean, 1e-5, 1e-6));
    EXPECT_TRUE(torch::allclose(r.running_var, whole.running_var, 1e-5, 1e-6));
    EXPECT_TRUE(torch::equal(r.tracked, whole.tracked));
  }
}

TEST(DistributedTest, SynchronizedBatchNorm2dIsTheWholeBatchs) {
  SKIP_WITHOUT_GLOO();
  torch::manual_seed(1);
  const torch::Tensor x = torch::randn({5, 3, 4, 6}) * 3 + 2;
  ExpectSynchronizedEqualsWholeBatch<torch::nn::BatchNorm2d, internal::BatchNorm2dSync>(x, 3);
}

TEST(DistributedTest, SynchronizedBatchNorm1dIsTheWholeBatchsWithAnEmptyRank) {
  SKIP_WITHOUT_GLOO();
  torch::manual_seed(2);
  const torch::Tensor x = torch::randn({7, 4}) - 1;
  ExpectSynchronizedEqualsWholeBatch<torch::nn::BatchNorm1d, internal::BatchNorm1dSync>(x, 4);
  // A rank with no rows (det3d's auxiliary points) still takes part.
  ExpectSynchronizedEqualsWholeBatch<torch::nn::BatchNorm1d, internal::BatchNorm1dSync>(x, 0);
}

TEST(DistributedTest, WithoutAGroupTheBatchNormIsLibTorchsBitForBit) {
  torch::manual_seed(4);
  const torch::Tensor x = torch::randn({4, 3, 5, 5});
  torch::nn::BatchNorm2d plain(3);
  internal::BatchNorm2dSync sync(3);
  EXPECT_EQ(internal::AttachGroup(*sync, nullptr), 1);
  EXPECT_TRUE(torch::equal(plain->forward(x), sync->forward(x)));
  EXPECT_TRUE(torch::equal(plain->running_var, sync->running_var));
  plain->eval();
  sync->eval();
  EXPECT_TRUE(torch::equal(plain->forward(x), sync->forward(x)));
  // The same names, so model.pt and checkpoints do not change.
  std::vector<std::string> a, b;
  for (const auto& p : plain->named_parameters()) a.push_back(p.key());
  for (const auto& p : plain->named_buffers()) a.push_back(p.key());
  for (const auto& p : sync->named_parameters()) b.push_back(p.key());
  for (const auto& p : sync->named_buffers()) b.push_back(p.key());
  EXPECT_EQ(a, b);
  // A plain batch norm left in a network is refused.
  torch::nn::Sequential net(torch::nn::Conv2d(3, 3, 1), torch::nn::BatchNorm2d(3));
  EXPECT_THROW(internal::AttachGroup(*net, nullptr), std::logic_error);
}

// Three layers with weights set by hand (the rank threads share LibTorch's generator).
struct ThreeLayers {
  torch::nn::Linear a{3, 4}, b{4, 4}, c{4, 2};
  ThreeLayers() {
    torch::NoGradGuard no_grad;
    double k = 0;
    for (torch::Tensor& p : Parameters()) {
      p.copy_(torch::arange(p.numel(), torch::kFloat32).reshape(p.sizes()) * 0.01 + 0.1 * ++k);
    }
  }
  std::vector<torch::Tensor> Parameters() {
    std::vector<torch::Tensor> params;
    for (auto* m : {&a, &b, &c}) {
      for (const torch::Tensor& p : (*m)->parameters()) params.push_back(p);
    }
    return params;
  }
  // Rank 1's graph never reaches c.
  torch::Tensor Loss(int rank) {
    const double r = rank + 1;
    const torch::Tensor h = b(torch::tanh(a(torch::full({2, 3}, r))));
    return rank == 0 ? h.sum() + c(h).pow(2).sum() * r : h.sum() * r;
  }
};

TEST(DistributedTest, GradientsAreSummedOverlappedInBucketOrderAndUnreachedOnesAddZeros) {
  SKIP_WITHOUT_GLOO();
  const TestTempDir dir("distributed");
  const auto errors =
      RunRanks(2, "file://" + (dir.path() / "store").string(), [](TrainingGroup& g) {
        // Expected: each rank's own gradients (zeros where its graph did not reach), summed.
        ThreeLayers plain;
        plain.Loss(g.rank()).backward();
        std::vector<torch::Tensor> expected;
        for (const torch::Tensor& p : plain.Parameters()) {
          expected.push_back(p.grad().defined() ? p.grad().clone() : torch::zeros_like(p));
        }
        internal::AllReduceSumInPlace(g, expected);

        ThreeLayers net;
        internal::GradientReducer reducer(g, net.Parameters(), /*bucket_bytes=*/40);
        EXPECT_EQ(reducer.num_buckets(), 5);    // c's weight and bias share one (40 bytes)
        for (int step = 0; step < 2; ++step) {  // a second backward starts from scratch
          for (torch::Tensor& p : net.Parameters()) p.mutable_grad() = torch::Tensor();
          reducer.Backward(net.Loss(g.rank()));
          const std::vector<torch::Tensor> params = net.Parameters();
          for (size_t i = 0; i < params.size(); ++i) {
            EXPECT_TRUE(torch::allclose(params[i].grad(), expected[i], 1e-6, 1e-6))
                << "step " << step << ", parameter " << i;
          }
        }
        // Rank 0's weights everywhere.
        torch::nn::Linear d(2, 2);
        {
          torch::NoGradGuard no_grad;
          d->weight.fill_(g.rank());
        }
        internal::BroadcastModuleState(g, *d);
        EXPECT_TRUE(torch::equal(d->weight, torch::zeros({2, 2})));
      });
  ExpectNoErrors(errors);
}

TEST(DistributedTest, AllReduceWithGradientSendsTheSumOfGradientsBack) {
  SKIP_WITHOUT_GLOO();
  const TestTempDir dir("distributed");
  const auto errors =
      RunRanks(2, "file://" + (dir.path() / "store").string(), [](TrainingGroup& g) {
        const double r = g.rank() + 1;  // ranks hold 1 and 2; the sum is 3
        const torch::Tensor x = torch::full({1}, r, torch::kFloat64).requires_grad_(true);
        const torch::Tensor s = internal::AllReduceSumWithGradient(&g, x);
        EXPECT_EQ(s.item<double>(), 3.0);
        // Rank r's loss is r * s: the whole loss is 3 s, so d/dx of it is 3 on both ranks.
        (r * s).sum().backward();
        EXPECT_EQ(x.grad().item<double>(), 3.0);
        EXPECT_EQ(internal::GlobalCount(&g, r), 3.0);
      });
  ExpectNoErrors(errors);
  EXPECT_EQ(internal::GlobalCount(nullptr, 7.0), 7.0);
}

}  // namespace
}  // namespace stereodet
