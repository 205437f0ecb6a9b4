// How subspace identification (identification/subspace.hpp) scales with the record length:
// MOESP, order 2, two inputs, one output, 15 block rows, one data set of 100 k, 400 k and 1.4 M
// samples. "before" is the code as it was (the whole block-Hankel matrix H^T, samples x 90,
// factorised at once, and the B, D, x0 regression formed whole: memory grows with the samples),
// kept here as the baseline; "after" is `identify` (H^T a block of columns at a time into a
// 90 x 90 triangular factor, the regression reduced the same way). Each run is a child process
// (fork) so that its peak resident memory is its own: the counters `peak_MB` (getrusage
// ru_maxrss of the child: the data, about 34 MB at 1.4 M samples, plus what identify allocates)
// and `seconds` (identify alone, wall clock). BM_IdentifyScaling_same_model compares the two
// models on 100 k samples (relative difference of their simulated outputs). Goal at 1.4 M
// samples: <= 200 MB and <= 6 s. Results: docs/performance.md.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <endohaptics/identification/subspace.hpp>
#include <random>
#include <string_view>

#include "smoke_pass.hpp"

namespace identification_scaling_bench {

namespace {

namespace id = endohaptics::identification;
namespace ds = endohaptics::identification::detail::subspace;
using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// A hundredth of the samples under the smoke pass (smoke_pass.hpp).
Index run_samples(Index full) { return bench::smoke_scaled<Index>(full, 100); }

// Order 2 (poles 0.875 +- 0.198i), inputs white, 5 % output noise.
id::DataSet make_data(Index samples) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  const MatrixXd A{{0.9, 0.2}, {-0.2, 0.85}};
  const MatrixXd B{{1.0, 0.5}, {0.0, 1.0}};
  const MatrixXd C{{1.0, 0.3}};
  const MatrixXd D{{0.1, 0.0}};
  const endohaptics::model::DynamicStateSpace<> system(A, B, C, D, 0.01);
  id::DataSet d{MatrixXd(samples, 2), MatrixXd()};
  for (Index i = 0; i < d.u.size(); ++i) d.u.data()[i] = normal(rng);
  d.y = id::simulate(system, d.u, VectorXd{{1.0, -1.0}});
  for (Index k = 0; k < samples; ++k) d.y(k, 0) += 0.05 * normal(rng);
  return d;
}

id::SubspaceOptions options() {
  id::SubspaceOptions o;
  o.order = 2;
  o.sample_time = 0.01;
  return o;
}

// The code before the streaming factorisation, MOESP with a given order and unscaled data (what
// identify does for this data), one data set: H^T whole and one QR; B, D, x0 from the whole
// regression matrix.
id::SubspaceModel identify_before(const id::DataSet& d, const id::SubspaceOptions& o) {
  const Index nu = d.u.cols(), ny = d.y.cols(), N = d.u.rows();
  const int s = id::default_block_rows(N, 1, static_cast<int>(nu), static_cast<int>(ny), o.order);
  const Index a = s * nu, p = s * (nu + ny), f = s * ny, r = a + p + f;
  const Index jn = N - 2 * s + 1;
  MatrixXd Ht(jn, r);
  for (Index i = 0; i < s; ++i) {
    for (Index m = 0; m < nu; ++m) {
      Ht.block(0, i * nu + m, jn, 1) = d.u.block(s + i, m, jn, 1);
      Ht.block(0, a + i * nu + m, jn, 1) = d.u.block(i, m, jn, 1);
    }
    for (Index m = 0; m < ny; ++m) {
      Ht.block(0, a + a + i * ny + m, jn, 1) = d.y.block(i, m, jn, 1);
      Ht.block(0, a + p + i * ny + m, jn, 1) = d.y.block(s + i, m, jn, 1);
    }
  }
  Eigen::HouseholderQR<Eigen::Ref<MatrixXd>> qr(Ht);
  const MatrixXd L = qr.matrixQR().topRows(r).triangularView<Eigen::Upper>().transpose();
  const MatrixXd L32 = L.block(a + p, a, f, p);
  const Eigen::JacobiSVD<MatrixXd> svd(L32, Eigen::ComputeThinU);
  const int n = o.order;
  const MatrixXd Gamma =
      svd.matrixU().leftCols(n) * svd.singularValues().head(n).cwiseSqrt().asDiagonal();
  const MatrixXd C = Gamma.topRows(ny);
  const MatrixXd A = Gamma.topRows(f - ny).colPivHouseholderQr().solve(Gamma.bottomRows(f - ny));
  // [x0 | vec(B) | vec(D)] regression, N ny rows.
  const Index cols = n + n * nu + ny * nu;
  MatrixXd Phi = MatrixXd::Zero(N * ny, cols);
  VectorXd rhs(N * ny);
  Phi.leftCols(n) = ds::free_response(A, C, N);
  MatrixXd X = MatrixXd::Zero(n, n * nu), next(n, n * nu);
  for (Index k = 0; k < N; ++k) {
    Phi.block(k * ny, n, ny, n * nu).noalias() = C * X;
    for (Index j = 0; j < nu; ++j) {
      for (Index i = 0; i < ny; ++i) Phi(k * ny + i, n + n * nu + j * ny + i) = d.u(k, j);
    }
    rhs.segment(k * ny, ny) = d.y.row(k).transpose();
    next.noalias() = A * X;
    for (Index j = 0; j < nu; ++j) next.block(0, j * n, n, n).diagonal().array() += d.u(k, j);
    X.swap(next);
  }
  const VectorXd theta = ds::scaled_least_squares(std::move(Phi), rhs, "identify (B, D, x0)");
  endohaptics::model::DynamicStateSpace<> ss(
      A, Eigen::Map<const MatrixXd>(theta.data() + n, n, nu), C,
      Eigen::Map<const MatrixXd>(theta.data() + n + n * nu, ny, nu), o.sample_time);
  ss.reset(theta.head(n));
  return id::SubspaceModel{.state_space = std::move(ss),
                           .initial_states = {theta.head(n)},
                           .singular_values = svd.singularValues(),
                           .order_singular_values = svd.singularValues(),
                           .order = n,
                           .block_rows = s,
                           .input_scale = VectorXd::Ones(nu),
                           .output_scale = VectorXd::Ones(ny)};
}

// One run in a child process: its identify time and peak resident memory.
struct ChildRun {
  double seconds = 0.0;
  double peak_mb = 0.0;
  int ok = 0;
};

template <typename Fit>
ChildRun in_child(Index samples, Fit fit) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    ChildRun run;
    const id::DataSet d = make_data(samples);
    const auto t0 = std::chrono::steady_clock::now();
    const id::SubspaceModel m = fit(d);
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    run.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB -> MiB
    run.ok = m.order == 2 ? 1 : 0;
    const auto written = write(fds[1], &run, sizeof run);
    _exit(written == static_cast<ssize_t>(sizeof run) ? 0 : 1);
  }
  close(fds[1]);
  ChildRun run;
  if (pid < 0 || read(fds[0], &run, sizeof run) != static_cast<ssize_t>(sizeof run)) run.ok = 0;
  close(fds[0]);
  if (pid > 0) waitpid(pid, nullptr, 0);
  return run;
}

template <typename Fit>
void measure(benchmark::State& state, Fit fit) {
  const Index samples = run_samples(state.range(0));
  ChildRun last;
  for (auto _ : state) {
    last = in_child(samples, fit);
    if (last.ok == 0) {
      state.SkipWithError("the child process failed");
      break;
    }
    state.SetIterationTime(last.seconds);
  }
  state.counters["samples"] = static_cast<double>(samples);
  state.counters["seconds"] = last.seconds;
  state.counters["peak_MB"] = last.peak_mb;
}

void BM_IdentifyScaling_before(benchmark::State& state) {
  measure(state, [](const id::DataSet& d) { return identify_before(d, options()); });
}
BENCHMARK(BM_IdentifyScaling_before)
    ->Arg(100'000)
    ->Arg(400'000)
    ->Arg(1'400'000)
    ->Iterations(1)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

void BM_IdentifyScaling_after(benchmark::State& state) {
  measure(state, [](const id::DataSet& d) { return id::identify(d.u, d.y, options()); });
}
BENCHMARK(BM_IdentifyScaling_after)
    ->Arg(100'000)
    ->Arg(400'000)
    ->Arg(1'400'000)
    ->Iterations(1)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// The two models on the same data: simulated outputs (each from its own x0) and the singular
// values, relative differences; both at rounding level.
void BM_IdentifyScaling_same_model(benchmark::State& state) {
  const id::DataSet d = make_data(run_samples(state.range(0)));
  double output_difference = 0.0, singular_value_difference = 0.0;
  for (auto _ : state) {
    const id::SubspaceModel before = identify_before(d, options());
    const id::SubspaceModel after = id::identify(d.u, d.y, options());
    const MatrixXd y_before = id::simulate(before, d.u, before.initial_states[0]);
    const MatrixXd y_after = id::simulate(after, d.u, after.initial_states[0]);
    output_difference = (y_after - y_before).norm() / y_before.norm();
    singular_value_difference =
        (after.singular_values - before.singular_values).norm() / before.singular_values.norm();
  }
  state.counters["output_rel_diff"] = output_difference;
  state.counters["sv_rel_diff"] = singular_value_difference;
}
BENCHMARK(BM_IdentifyScaling_same_model)
    ->Arg(100'000)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

}  // namespace identification_scaling_bench
