// The JointForceModel conformance suite: one set of checks that every joint force model runs
// (the way manif's MANIF_TEST and Sophus's Tests<Group> test every group): non-finite input,
// reset, state round trip, no allocation, determinism and bounded output. A new model (ours or a
// user's) joins by a Factory specialisation and one entry in the TEST_CASE_TEMPLATE lists.
#include "alloc_counter.hpp"  // first: counts every heap allocation of this executable

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "endohaptics/estimation/any_joint_force_model.hpp"
#include "endohaptics/estimation/bidirectional_load_observer.hpp"
#include "endohaptics/estimation/clamp_2016_as_run.hpp"
#include "endohaptics/estimation/clamp_presets.hpp"
#include "endohaptics/estimation/force_models_2016.hpp"
#include "endohaptics/estimation/joint_force_model.hpp"
#include "endohaptics/estimation/push_load_observer.hpp"
#include "endohaptics/estimation/simulate.hpp"
#include "endohaptics/estimation/stall_hold.hpp"

namespace estimation_joint_force_model_conformance_test {

namespace est = endohaptics::estimation;
using endohaptics::model::NumericStatus;

// An AnyJointForceModel of the four identified kinds, holding an observer.
using AnyClamp =
    est::AnyJointForceModel<est::ClampModel2016<double>, est::StallHold<double>,
                            est::PushLoadObserver<double>, est::BidirectionalLoadObserver<double>>;

// A configured instance of each model under test.
template <typename M>
struct Factory;
template <typename S>
struct Factory<est::StallHold<S>> {
  static est::StallHold<S> make() {
    est::StallHoldParameters<S> p;
    p.gain = S(-7.5);
    p.side = est::StallHoldSide::negative;
    return est::StallHold<S>(p);
  }
};
template <>
struct Factory<est::PushLoadObserver<double>> {
  static est::PushLoadObserver<double> make() {
    est::PushLoadObserverParameters<double> p;
    p.current_per_load = 1.45;
    p.current_offset = 0.07;
    p.back_current_per_load = 0.8;
    p.back_variance = 4e-4;
    p.load_per_angle = 0.1;
    return est::PushLoadObserver<double>(p);
  }
};
template <>
struct Factory<est::BidirectionalLoadObserver<double>> {
  static est::BidirectionalLoadObserver<double> make() {
    est::BidirectionalLoadObserverParameters<double> p;
    p.forward_gain = -1.41e-3;
    p.forward_gain_stroke = -2.3e-4;
    p.forward_offset = 0.066;
    p.backward_gain = -6.1e-4;
    p.backward_offset = -0.09;
    p.forward_variance = 9000.0;
    p.backward_variance = 30000.0;
    p.friction_variance = 62.0;
    p.load_process_variance = 0.002;
    p.initial_variance = 1180.0;
    p.output_shape << 0.2, 0.25, -0.38, 1.15, 1.1, 0.66, 0.12, -0.78;
    return est::BidirectionalLoadObserver<double>(p);
  }
};
template <>
struct Factory<est::ClampModel2016<double>> {
  static est::ClampModel2016<double> make() { return est::models_2016<double>().clamp1; }
};
template <>
struct Factory<est::RollModel2016<double>> {
  static est::RollModel2016<double> make() { return est::models_2016<double>().roll; }
};
template <>
struct Factory<est::Clamp2016AsRun<double>> {
  static est::Clamp2016AsRun<double> make() { return est::Clamp2016AsRun<double>(); }
};
template <>
struct Factory<est::Clamp2016AsRun<float>> {
  static est::Clamp2016AsRun<float> make() { return est::Clamp2016AsRun<float>(); }
};
template <>
struct Factory<est::IdentifiedHammersteinWiener<double>> {
  static est::IdentifiedHammersteinWiener<double> make() {
    // With a current play, whose output is part of the state.
    return est::IdentifiedHammersteinWiener<double>(est::models_2016<double>().clamp1.model(),
                                                    endohaptics::model::FreeMotionThreshold(0.2),
                                                    0.15);
  }
};
template <>
struct Factory<est::BridgeJointModel> {
  static est::BridgeJointModel make() {
    return est::preset_force_models(est::ClampPreset::clamp2016_as_run).clamp1;
  }
};
template <>
struct Factory<AnyClamp> {
  static AnyClamp make() {
    return AnyClamp(Factory<est::BidirectionalLoadObserver<double>>::make());
  }
};

// Seeded, bounded signals that move both ways, stall and push (|current| <= 2 A, |velocity| <=
// 5 rad/s), the position their running sum.
template <typename S>
std::vector<est::JointSignals<S>> signals(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-0.05, 0.05);
  std::vector<est::JointSignals<S>> out(static_cast<std::size_t>(n));
  double position = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = 1e-3 * k;
    const double velocity = 4.0 * std::sin(2.0 * 3.141592653589793 * 0.7 * t) + noise(rng);
    position += velocity * 1e-3;
    const double current = 1.5 * std::sin(2.0 * 3.141592653589793 * 0.3 * t) + noise(rng);
    out[static_cast<std::size_t>(k)] = {static_cast<S>(position), static_cast<S>(velocity),
                                        static_cast<S>(current), S(0)};
  }
  return out;
}

template <typename M>
std::vector<typename M::ScalarType> run(
    M& m, const std::vector<est::JointSignals<typename M::ScalarType>>& s) {
  using S = typename M::ScalarType;
  Eigen::Matrix<S, Eigen::Dynamic, 1> y(static_cast<Eigen::Index>(s.size()));
  const est::SimulationResult r = est::simulate(
      m, [&](Eigen::Index k) noexcept { return s[static_cast<std::size_t>(k)]; }, y);
  REQUIRE(r.ok());
  return {y.data(), y.data() + y.size()};
}

#define ENDOHAPTICS_JOINT_FORCE_MODELS                                          \
  est::StallHold<double>, est::StallHold<float>, est::PushLoadObserver<double>, \
      est::BidirectionalLoadObserver<double>, est::ClampModel2016<double>,      \
      est::RollModel2016<double>, AnyClamp, est::Clamp2016AsRun<double>,        \
      est::Clamp2016AsRun<float>, est::IdentifiedHammersteinWiener<double>, est::BridgeJointModel

TEST_CASE_TEMPLATE("joint force models: a non-finite signal is refused, the state untouched", M,
                   ENDOHAPTICS_JOINT_FORCE_MODELS) {
  static_assert(est::JointForceModel<M>);
  using S = typename M::ScalarType;
  M m = Factory<M>::make();
  const auto s = signals<S>(300, 1);
  (void)run(m, s);
  for (const S bad : {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(),
                      -std::numeric_limits<S>::infinity()}) {
    for (int which = 0; which < 3; ++which) {
      CAPTURE(which);
      const typename M::State before = m.state();
      est::JointSignals<S> x = s.back();
      (which == 0 ? x.position : which == 1 ? x.velocity : x.current) = bad;
      const NumericStatus status = m.advance(x);
      // A signal the model does not read may pass; one it reads is refused, all or nothing.
      CHECK((status == NumericStatus::ok || status == NumericStatus::non_finite_input));
      if (status != NumericStatus::ok) CHECK(m.state() == before);
      CHECK(m.state().allFinite());
      CHECK(std::isfinite(m.force(s.back())));
      m.reset(before);
    }
  }
}

TEST_CASE_TEMPLATE("joint force models: reset() starts over as constructed", M,
                   ENDOHAPTICS_JOINT_FORCE_MODELS) {
  using S = typename M::ScalarType;
  const M fresh = Factory<M>::make();
  M m = fresh;
  const auto s = signals<S>(500, 2);
  const auto first = run(m, s);
  m.reset();
  CHECK(m.state() == fresh.state());
  CHECK(run(m, s) == first);  // bit for bit
}

TEST_CASE_TEMPLATE("joint force models: state() and reset(state) restore exactly", M,
                   ENDOHAPTICS_JOINT_FORCE_MODELS) {
  using S = typename M::ScalarType;
  M m = Factory<M>::make();
  const auto s = signals<S>(400, 3);
  (void)run(m, s);
  const typename M::State saved = m.state();
  M copy = m;
  const auto tail = signals<S>(100, 4);
  const auto ahead = run(m, tail);
  m.reset(saved);
  CHECK(m.state() == saved);
  CHECK(run(m, tail) == run(copy, tail));
  (void)ahead;
}

TEST_CASE_TEMPLATE("joint force models: 10,000 steps allocate nothing", M,
                   ENDOHAPTICS_JOINT_FORCE_MODELS) {
  using S = typename M::ScalarType;
  M m = Factory<M>::make();
  const auto s = signals<S>(10000, 5);
  S sum = 0;
  bool ok = true;
  const long allocations = endohaptics::test::allocations_during([&] {
    for (const auto& x : s) {
      ok = ok && m.advance(x) == NumericStatus::ok;
      sum += m.force(x);
      sum += m.state()[0];
    }
    m.reset();
  });
  CHECK(ok);
  CHECK(allocations == 0);
  CHECK(std::isfinite(sum));
}

TEST_CASE_TEMPLATE("joint force models: deterministic, the same signals give the same forces", M,
                   ENDOHAPTICS_JOINT_FORCE_MODELS) {
  using S = typename M::ScalarType;
  M a = Factory<M>::make();
  M b = Factory<M>::make();
  const auto s = signals<S>(3000, 6);
  CHECK(run(a, s) == run(b, s));
  CHECK(a.state() == b.state());
}

TEST_CASE_TEMPLATE("joint force models: bounded signals give a bounded, finite force", M,
                   ENDOHAPTICS_JOINT_FORCE_MODELS) {
  using S = typename M::ScalarType;
  M m = Factory<M>::make();
  for (const unsigned seed : {7u, 8u, 9u}) {
    const auto y = run(m, signals<S>(10000, seed));
    double peak = 0.0;
    for (const S v : y) {
      REQUIRE(std::isfinite(v));
      peak = std::fmax(peak, std::fabs(static_cast<double>(v)));
    }
    // The joint models' parameter bound: no estimate of a plausible signal comes near it.
    CHECK(peak <= est::max_joint_model_parameter);
    CHECK(m.state().allFinite());
  }
}

}  // namespace estimation_joint_force_model_conformance_test
