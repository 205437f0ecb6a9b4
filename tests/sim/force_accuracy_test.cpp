#include <doctest/doctest.h>

#include <cmath>
#include <endohaptics/sim/force_accuracy.hpp>
#include <numbers>
#include <vector>

namespace sim_force_accuracy_test {

namespace sim = endohaptics::sim;

namespace {
struct Series {
  std::vector<double> t, f;
};
// A force pulse train sampled every `dt` from `t0`, delayed by `delay`, scaled by `gain`.
Series pulses(double t0, double dt, int n, double delay = 0.0, double gain = 1.0) {
  Series s;
  for (int i = 0; i < n; ++i) {
    const double t = t0 + dt * i;
    const double phase = std::fmod(t - delay, 2.0);
    const double f =
        phase > 0.5 && phase < 1.5 ? 2.0 * std::sin(std::numbers::pi * (phase - 0.5)) : 0.0;
    s.t.push_back(t);
    s.f.push_back(gain * f);
  }
  return s;
}
}  // namespace

TEST_CASE("a perfect estimate on another time grid: fit 100 %, correlation 1, no delay") {
  const Series truth = pulses(0.0, 1e-3, 10000);
  const Series est = pulses(0.0003, 0.7e-3, 14000);  // irregular relative to the truth's grid
  const auto a = sim::force_accuracy(truth.t, truth.f, est.t, est.f);
  CHECK(a.fit_percent > 99.5);
  CHECK(a.correlation > 0.9999);
  CHECK(a.delay == doctest::Approx(0.0));
  CHECK(a.rmse < 0.01);
  CHECK(a.truth_peak == doctest::Approx(2.0).epsilon(1e-3));
  CHECK(a.span == doctest::Approx(9.7997).epsilon(1e-3));
}

TEST_CASE("a delayed, attenuated estimate: the delay is found and the fits say how good it is") {
  const Series truth = pulses(0.0, 1e-3, 10000);
  const Series est = pulses(0.0, 1e-3, 10000, 0.040, 0.5);
  const auto a = sim::force_accuracy(truth.t, truth.f, est.t, est.f);
  CHECK(a.delay == doctest::Approx(0.040).epsilon(1e-6));
  CHECK(a.correlation_at_delay > 0.9999);
  CHECK(a.correlation < a.correlation_at_delay);
  // Once aligned the estimate is y/2 on the first m = n - 300 grid points (300 = the lags
  // searched): fit = 100 (1 - ||y/2|| / ||y - mean y||) over those points, written out here.
  const std::size_t m = a.samples - 300;
  double num = 0, den = 0, mean = 0;
  for (std::size_t i = 0; i < m; ++i) mean += truth.f[i];
  mean /= static_cast<double>(m);
  for (std::size_t i = 0; i < m; ++i) {
    num += 0.25 * truth.f[i] * truth.f[i];
    den += (truth.f[i] - mean) * (truth.f[i] - mean);
  }
  CHECK(a.fit_percent_at_delay ==
        doctest::Approx(100.0 * (1.0 - std::sqrt(num / den))).epsilon(1e-6));
  CHECK(a.fit_percent < a.fit_percent_at_delay);
}

TEST_CASE("bad series are refused with a message") {
  const Series ok = pulses(0.0, 1e-3, 2000);
  std::vector<double> t_back = ok.t;
  t_back[10] = t_back[9];
  CHECK_THROWS_WITH_AS((void)sim::force_accuracy(t_back, ok.f, ok.t, ok.f),
                       doctest::Contains("not strictly increasing at sample 10"),
                       endohaptics::Error);
  std::vector<double> f_nan = ok.f;
  f_nan[5] = std::nan("");
  CHECK_THROWS_WITH_AS((void)sim::force_accuracy(ok.t, ok.f, ok.t, f_nan),
                       doctest::Contains("estimate sample 5 is not finite"), endohaptics::Error);
  const Series late = pulses(5.0, 1e-3, 2000);
  CHECK_THROWS_WITH_AS((void)sim::force_accuracy(ok.t, ok.f, late.t, late.f),
                       doctest::Contains("overlap"), endohaptics::Error);
  CHECK_THROWS_AS(
      (void)sim::force_accuracy(std::vector<double>{0.0}, std::vector<double>{1.0}, ok.t, ok.f),
      endohaptics::Error);
}

}  // namespace sim_force_accuracy_test
