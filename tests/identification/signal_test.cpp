#include "endohaptics/identification/signal.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "endohaptics/files/log_reader.hpp"
#include "shared_data.hpp"

namespace identification_signal_test {

namespace {

namespace id = endohaptics::identification;
using endohaptics::Error;

// The deterministic test signal of the scipy references below:
//   k = np.arange(60); x = np.sin(0.3*k) + 0.5*np.sin(2.1*k) + 0.02*k
Eigen::VectorXd test_signal() {
  Eigen::VectorXd x(60);
  for (int k = 0; k < 60; ++k) {
    x[k] = std::sin(0.3 * k) + 0.5 * std::sin(2.1 * k) + 0.02 * k;
  }
  return x;
}

bool close(double a, double b, double rel = 1e-12, double abs = 1e-14) {
  return std::abs(a - b) <= abs + rel * std::abs(b);
}

struct Reference {
  Eigen::Index index;
  double value;
};

void check_values(const Eigen::VectorXd& y, const std::vector<Reference>& refs,
                  double rel = 1e-11) {
  for (const Reference& ref : refs) {  // no structured binding: clang 14 cannot capture one
    const auto i = ref.index;
    const double v = ref.value;
    INFO("index " << i << ": got " << y[i] << ", want " << v);
    CHECK(close(y[i], v, rel, 1e-13));
  }
}

}  // namespace

// All scipy numbers below: Debian /usr/bin/python3, scipy 1.10.1, numpy 1.24.2, printed with
// repr() by the script in the comment of each case.

TEST_CASE("butterworth_lowpass equals scipy.signal.butter(N, fc, fs=1/ts, output='sos')") {
  // for (N, fc, ts) in cases: print(sg.butter(N, fc, fs=1/ts, output='sos'))
  struct Case {
    int order;
    double cutoff;
    double ts;
    std::vector<std::vector<double>> sos;
  };
  const std::vector<Case> cases = {
      {4,
       20.0,
       0.02,  // worksheet 4.2.1: 20 Hz, at the 50 Hz of the logs
       {{0.43284664499029185, 0.8656932899805837, 0.43284664499029185, 1.0, 1.0485995763626113,
         0.2961403575616694},
        {1.0, 2.0, 1.0, 1.0, 1.320913430819426, 0.6327387928852763}}},
      {3,
       5.0,
       0.02,
       {{0.018098933007514435, 0.03619786601502887, 0.018098933007514435, 1.0, -0.5095254494944288,
         0.0},
        {1.0, 1.0, 0.0, 1.0, -1.2505164308487398, 0.5457233155094575}}},
      {5,
       2.0,
       0.01,
       {{8.04235642197117e-07, 1.608471284394234e-06, 8.04235642197117e-07, 1.0, -0.881618592363189,
         0.0},
        {1.0, 2.0, 1.0, 1.0, -1.8015573988553768, 0.8158761244727529},
        {1.0, 1.0, 0.0, 1.0, -1.910245408589122, 0.9254279833351826}}},
      {1,
       10.0,
       0.01,
       {{0.2452372752527856, 0.2452372752527856, 0.0, 1.0, -0.5095254494944288, 0.0}}},
      {3,
       20.0,
       0.02,  // above fs/4: the zero at the origin pairs with the other section
       {{0.5276243825019432, 0.5276243825019432, 0.0, 1.0, 0.5095254494944288, 0.0},
        {1.0, 2.0, 1.0, 1.0, 1.2505164308487398, 0.5457233155094575}}},
      {6,
       1.0,
       0.001,
       {{9.498089386097797e-16, 1.8996178772195594e-15, 9.498089386097797e-16, 1.0,
         -1.9878958801798439, 0.9879351203171739},
        {1.0, 2.0, 1.0, 1.0, -1.9911142922016536, 0.9911535958689355},
        {1.0, 2.0, 1.0, 1.0, -1.9967134716131187, 0.9967528858055902}}},
      {2,
       12.5,
       0.02,
       {{0.2928932188134525, 0.585786437626905, 0.2928932188134525, 1.0, 0.0, 0.1715728752538099}}},
  };
  for (const auto& c : cases) {
    const id::SosMatrix sos = id::butterworth_lowpass(c.order, c.cutoff, c.ts);
    REQUIRE(sos.rows() == static_cast<Eigen::Index>(c.sos.size()));
    for (Eigen::Index r = 0; r < sos.rows(); ++r) {
      for (Eigen::Index k = 0; k < 6; ++k) {
        const double want = c.sos[static_cast<std::size_t>(r)][static_cast<std::size_t>(k)];
        INFO("order " << c.order << " cutoff " << c.cutoff << " section " << r << " coeff " << k
                      << ": " << sos(r, k) << " vs " << want);
        CHECK(close(sos(r, k), want, 1e-12, 1e-15));
      }
    }
    // Unit gain at DC (the product over sections of b(1)/a(1)).
    double dc = 1.0;
    for (Eigen::Index r = 0; r < sos.rows(); ++r) {
      dc *= sos.row(r).head<3>().sum() / sos.row(r).tail<3>().sum();
    }
    CHECK(dc == doctest::Approx(1.0).epsilon(1e-9));
  }
}

TEST_CASE("butterworth_lowpass: -3 dB at the cutoff, any order") {
  for (int order = 1; order <= 8; ++order) {
    const double ts = 0.01;
    const double fc = 7.0;
    const id::SosMatrix sos = id::butterworth_lowpass(order, fc, ts);
    const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * fc * ts);
    std::complex<double> h(1.0, 0.0);
    for (Eigen::Index r = 0; r < sos.rows(); ++r) {
      h *= (sos(r, 0) + sos(r, 1) / z + sos(r, 2) / (z * z)) /
           (sos(r, 3) + sos(r, 4) / z + sos(r, 5) / (z * z));
    }
    INFO("order " << order);
    CHECK(std::abs(h) == doctest::Approx(std::sqrt(0.5)).epsilon(1e-12));
  }
}

TEST_CASE("butterworth_lowpass rejects invalid designs") {
  CHECK_THROWS_AS((void)id::butterworth_lowpass(0, 5.0, 0.02), Error);
  CHECK_THROWS_AS((void)id::butterworth_lowpass(33, 5.0, 0.02), Error);
  CHECK_THROWS_AS((void)id::butterworth_lowpass(4, 25.0, 0.02), Error);  // = Nyquist
  CHECK_THROWS_AS((void)id::butterworth_lowpass(4, 0.0, 0.02), Error);
  CHECK_THROWS_AS((void)id::butterworth_lowpass(4, 5.0, 0.0), Error);
  CHECK_THROWS_WITH_AS((void)id::butterworth_lowpass(4, 30.0, 0.02),
                       doctest::Contains("cutoff must lie in (0, 25) Hz"), Error);
}

TEST_CASE("sosfilt_zi, sosfilt and filtfilt equal scipy") {
  const Eigen::VectorXd x = test_signal();
  // print(repr(sg.sosfilt_zi(sg.butter(4, 5, fs=50, output='sos'))))
  const id::SosMatrix sos4 = id::butterworth_lowpass(4, 5.0, 0.02);
  const auto zi = id::sosfilt_zi(sos4);
  CHECK(close(zi(0, 0), 0.07313199715874638, 1e-11));
  CHECK(close(zi(0, 1), -0.01826167519702828, 1e-11));
  CHECK(close(zi(1, 0), 0.9220436594835376, 1e-11));
  CHECK(close(zi(1, 1), -0.5547824523688138, 1e-11));
  CHECK(id::filtfilt_padlen(sos4) == 15);

  // y1 = sg.sosfilt(sos, x); y = sg.sosfiltfilt(sos, x)   (default padtype 'odd')
  Eigen::Matrix<double, Eigen::Dynamic, 2> state =
      Eigen::Matrix<double, Eigen::Dynamic, 2>::Zero(2, 2);
  check_values(id::sosfilt(sos4, x, state), {{0, 0.0},
                                             {1, 0.003604387000387351},
                                             {2, 0.023772802388006588},
                                             {30, 1.5121287281271643},
                                             {59, 0.4298193450318963}});
  check_values(id::filtfilt(sos4, x), {{0, 0.0011328132725390988},
                                       {1, 0.3161327150096166},
                                       {7, 1.0010028886534785},
                                       {30, 1.0111171269256214},
                                       {52, 1.1520790860034538},
                                       {58, -0.05574571699084067},
                                       {59, -0.21532507105530727}});

  // Odd order: one section has b2 = a2 = 0, so scipy pads 3 * (2*2 + 1 - 1) = 12 samples.
  const id::SosMatrix sos3 = id::butterworth_lowpass(3, 8.0, 0.02);
  CHECK(id::filtfilt_padlen(sos3) == 12);
  check_values(id::filtfilt(sos3, x), {{0, -0.0004737802062118393},
                                       {1, 0.31563344268153265},
                                       {7, 1.0032328045616943},
                                       {30, 1.0120233361835158},
                                       {52, 1.1357433161868233},
                                       {58, 0.035840899910635764},
                                       {59, -0.2236887228143325}});
}

TEST_CASE("filtfilt: zero phase, |H|^2 gain, constants and ramps pass unchanged") {
  const double ts = 0.01;
  const double fc = 10.0;
  const id::SosMatrix sos = id::butterworth_lowpass(4, fc, ts);
  // A sinusoid at the cutoff comes out at half amplitude (|H|^2 = 1/2) and in phase.
  Eigen::VectorXd x(2000);
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    x[k] = std::sin(2.0 * std::numbers::pi * fc * ts * static_cast<double>(k));
  }
  const Eigen::VectorXd y = id::filtfilt(sos, x);
  for (Eigen::Index k = 800; k < 1200; ++k)
    CHECK(y[k] == doctest::Approx(0.5 * x[k]).epsilon(1e-3).scale(1));
  // A ramp is not reproduced exactly (the steady-state start assumes a constant): same error
  // as scipy. l = np.linspace(-3, 5, 100); y = sg.sosfiltfilt(sg.butter(4, 10, fs=100,
  // output='sos'), l): y[0] = -3.0008176240922038, y[50] = 1.0404040095865144,
  // max |y - l| = 0.002166924709099405.
  const Eigen::VectorXd line = Eigen::VectorXd::LinSpaced(100, -3.0, 5.0);
  const Eigen::VectorXd filtered_line = id::filtfilt(sos, line);
  CHECK(close(filtered_line[0], -3.0008176240922038, 1e-11));
  CHECK(close(filtered_line[50], 1.0404040095865144, 1e-11));
  CHECK(close((filtered_line - line).cwiseAbs().maxCoeff(), 0.002166924709099405, 1e-8));
  const Eigen::VectorXd flat = Eigen::VectorXd::Constant(40, -232.2464);
  CHECK((id::filtfilt(sos, flat) - flat).cwiseAbs().maxCoeff() < 1e-9);
  // Too short for the padding (scipy raises too).
  CHECK_THROWS_WITH_AS((void)id::filtfilt(sos, Eigen::VectorXd::Zero(15)),
                       doctest::Contains("needs more than 15 samples"), Error);
  CHECK_NOTHROW((void)id::filtfilt(sos, Eigen::VectorXd::Zero(16)));
}

TEST_CASE("savgol_filter equals scipy.signal.savgol_filter (mode='interp')") {
  const Eigen::VectorXd x = test_signal();
  // sg.savgol_filter(x, 7, 2, deriv=1, delta=0.02)
  check_values(id::savgol_filter(x, 7, 2, 1, 0.02),
               {{0, 17.464185619324233},
                {1, 14.275829609046097},
                {2, 11.087473598767966},
                {3, 7.89911758848983},
                {30, -12.743651756220348},
                {56, -4.902199956085595},
                {57, -6.44304731531204},
                {59, -9.524742033764936}},
               1e-10);
  // sg.savgol_filter(x, 5, 3, deriv=0)
  check_values(id::savgol_filter(x, 5, 3),
               {{0, 0.056328127661157246},
                {1, 0.5218123793411521},
                {2, 0.506823353155178},
                {30, 1.0305452146529377},
                {58, 0.5786620735677254},
                {59, -0.24351656369066255}},
               1e-10);
  // sg.savgol_filter(x, 9, 4, deriv=2, delta=0.01)
  check_values(id::savgol_filter(x, 9, 4, 2, 0.01),
               {{0, -5693.607857799359},
                {4, 577.3912588270637},
                {30, -92.95247938377588},
                {59, -7225.499389718013}},
               1e-9);
  CHECK_THROWS_AS((void)id::savgol_filter(x, 6, 2), Error);
  CHECK_THROWS_AS((void)id::savgol_filter(x, 5, 5), Error);
  CHECK_THROWS_AS((void)id::savgol_filter(x.head(4), 5, 2), Error);
}

TEST_CASE("central_difference equals numpy.gradient(x, ts), differentiate on raw stamps") {
  const Eigen::VectorXd x = test_signal();
  // np.gradient(x, 0.02)
  check_values(id::central_difference(x, 0.02), {{0, 37.35624449928883},
                                                 {1, 4.2213646797060305},
                                                 {30, 8.813008929851025},
                                                 {59, -36.056720110464404}});
  // On a uniform grid differentiate() is the same central difference.
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(60, 0.0, 59 * 0.02);
  CHECK((id::differentiate(t, x, 0.1) - id::central_difference(x, 0.02)).cwiseAbs().maxCoeff() <
        1e-9);

  // Irregular stamps with a 0.9 s hole after index 3 and an isolated sample at index 6.
  Eigen::VectorXd ti(9), xi(9);
  ti << 0.0, 0.01, 0.025, 0.03, 0.93, 0.94, 2.0, 3.0, 3.02;
  xi = 2.0 * ti.array() + 1.0;  // slope 2 everywhere
  xi[4] += 5.0;                 // a jump across the hole must not leak into the first stretch
  xi[5] += 5.0;
  const Eigen::VectorXd v = id::differentiate(ti, xi, 0.1);
  for (const Eigen::Index k : {0, 1, 2, 3, 4, 5, 7, 8}) CHECK(v[k] == doctest::Approx(2.0));
  CHECK(v[6] == 0.0);  // isolated between two gaps
  CHECK_THROWS_AS((void)id::differentiate(ti.reverse(), xi, 0.1), Error);
}

TEST_CASE("detrend equals scipy.signal.detrend") {
  const Eigen::VectorXd x = test_signal();
  // sg.detrend(x); sg.detrend(x, type='constant')
  check_values(id::detrend(x), {{0, -0.30571052434143514},
                                {1, 0.4309724615775756},
                                {30, 0.4768286890487521},
                                {59, -1.145090580961475}});
  check_values(id::detrend(x, id::DetrendType::constant),
               {{0, -0.613746694311025}, {59, -0.8370544109918854}});
}

TEST_CASE("resample_uniform interpolates linearly and splits at gaps instead of bridging them") {
  // 50 Hz with jitter, a 0.9 s hole after t = 0.1, then 50 Hz again.
  Eigen::VectorXd t(13);
  t << 0.0, 0.021, 0.04, 0.059, 0.08, 0.1, 1.0, 1.02, 1.041, 1.06, 1.08, 1.1, 1.12;
  Eigen::MatrixXd s(13, 2);
  s.col(0) = 3.0 * t.array() - 1.0;  // straight lines are reproduced exactly
  s.col(1) = -0.5 * t.array() + 4.0;
  const id::Segments r = id::resample_uniform(t, s, 0.02);
  CHECK(r.max_gap == doctest::Approx(0.1));  // 5 x max(ts, median step 0.02)
  CHECK(r.gaps == 1);
  CHECK(r.largest_step == doctest::Approx(0.9));
  REQUIRE(r.segments.size() == 2);
  CHECK(r.segments[0].rows() == 6);  // 0.00 .. 0.10
  CHECK(r.segments[1].rows() == 7);  // 1.00 .. 1.12
  CHECK(r.segments[0].first_source == 0);
  CHECK(r.segments[0].last_source == 5);
  CHECK(r.segments[1].first_source == 6);
  CHECK(r.segments[1].start_time == 1.0);
  CHECK(r.samples() == 13);
  CHECK(&r.longest() == &r.segments[1]);
  for (const auto& seg : r.segments) {
    const Eigen::VectorXd tg = seg.time();
    for (Eigen::Index k = 0; k < seg.rows(); ++k) {
      CHECK(seg.data(k, 0) == doctest::Approx(3.0 * tg[k] - 1.0).epsilon(1e-12));
      CHECK(seg.data(k, 1) == doctest::Approx(-0.5 * tg[k] + 4.0).epsilon(1e-12));
    }
  }
  // A stricter minimum drops the short stretch and counts it.
  const id::Segments strict = id::resample_uniform(t, s, 0.02, {0.0, 7});
  CHECK(strict.segments.size() == 1);
  CHECK(strict.dropped_segments == 1);
  CHECK(strict.dropped_source_rows == 6);
  // A threshold above the hole bridges it: one segment 0 .. 1.12 s.
  const id::Segments bridged = id::resample_uniform(t, s, 0.02, {1.0, 2});
  CHECK(bridged.segments.size() == 1);
  CHECK(bridged.segments[0].rows() == 57);

  Eigen::VectorXd bad = t;
  bad[4] = bad[3];
  CHECK_THROWS_WITH_AS((void)id::resample_uniform(bad, s, 0.02), doctest::Contains("time[4]"),
                       Error);
  Eigen::MatrixXd nan = s;
  nan(2, 1) = std::nan("");
  CHECK_THROWS_WITH_AS((void)id::resample_uniform(t, nan, 0.02),
                       doctest::Contains("row 2, column 1"), Error);
  CHECK_THROWS_AS((void)id::resample_uniform(t, s.topRows(5), 0.02), Error);
  CHECK_THROWS_AS((void)id::resample_uniform(t, s, -0.02), Error);
}

TEST_CASE("offset removal: mean or median of a window") {
  Eigen::VectorXd x(8);
  x << -232.0, -232.5, -231.0, -232.25, -200.0, 5.0, 6.0, 7.0;
  CHECK(id::estimate_offset(x, {0, 4, id::OffsetEstimator::median}) == -232.125);
  CHECK(id::estimate_offset(x, {0, 4, id::OffsetEstimator::mean}) == -231.9375);
  CHECK(id::estimate_offset(x, {0, 5, id::OffsetEstimator::median}) == -232.0);
  CHECK(id::estimate_offset(x, {5, -1, id::OffsetEstimator::mean}) == 6.0);
  Eigen::VectorXd y = x;
  CHECK(id::remove_offset(y, {0, 4}) == -232.125);
  CHECK(y[0] == 0.125);
  CHECK(y[7] == 239.125);
  CHECK_THROWS_AS((void)id::estimate_offset(x, {6, 3}), Error);
  CHECK_THROWS_AS((void)id::estimate_offset(x, {0, 0}), Error);
}

TEST_CASE("preprocess: resample, zero-phase low-pass, output offset from the first samples") {
  // 50 Hz, 10 s, a 0.5 s hole at 4 s; column 0 = 1 Hz sine + 12 Hz noise; column 1 = -230 offset
  // plus a slow sine.
  std::vector<double> tv;
  for (int k = 0; k < 500; ++k) {
    const double tk = 0.02 * k;
    if (tk > 4.0 && tk < 4.5) continue;
    tv.push_back(tk);
  }
  const Eigen::Map<const Eigen::VectorXd> t(tv.data(), static_cast<Eigen::Index>(tv.size()));
  Eigen::MatrixXd s(t.size(), 2);
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    s(k, 0) =
        std::sin(2 * std::numbers::pi * t[k]) + 0.3 * std::sin(2 * std::numbers::pi * 12 * t[k]);
    s(k, 1) = -230.0 + std::sin(2 * std::numbers::pi * 0.2 * t[k]);
  }
  id::PreprocessOptions o;
  o.sample_time = 0.02;
  o.cutoff = 4.0;
  o.offset_columns = {1};
  o.offset_duration = 0.1;  // first 5 samples: sin(0.2 * 2 pi t) < 0.11 there
  const id::Segments r = id::preprocess(t, s, o);
  REQUIRE(r.segments.size() == 2);
  CHECK(r.gaps == 1);
  CHECK(r.offsets[0] == 0.0);
  CHECK(r.offsets[1] ==
        doctest::Approx(-230.0 + std::sin(2 * std::numbers::pi * 0.2 * 0.04)).epsilon(1e-3));
  // The 12 Hz part is gone (4th-order filtfilt at 4 Hz: |H(12 Hz)|^2 ~ 1e-4), the 1 Hz part stays.
  const auto& seg = r.segments[0];
  for (Eigen::Index k = 40; k < 160; ++k) {
    const double tk = seg.start_time + 0.02 * static_cast<double>(k);
    CHECK(seg.data(k, 0) ==
          doctest::Approx(std::sin(2 * std::numbers::pi * tk)).scale(1).epsilon(2e-3));
  }
  id::PreprocessOptions bad = o;
  bad.offset_columns = {2};
  CHECK_THROWS_AS((void)id::preprocess(t, s, bad), Error);
  bad = o;
  bad.sample_time = 0;
  CHECK_THROWS_AS((void)id::preprocess(t, s, bad), Error);
}

TEST_CASE("real log: pitch-down-02 force filtered at 20 Hz as worksheet 4.2.1" *
          doctest::skip(!endohaptics::test::has_shared_data("endowrist-2016"))) {
  const auto log = endohaptics::files::read_endowrist_2016(
      endohaptics::test::shared_data("endowrist-2016/pitch/pitch-down-02.csv").string());
  id::PreprocessOptions o;
  o.sample_time = 0.02;
  o.cutoff = 20.0;
  o.offset_columns = {0};
  const id::Segments r = id::preprocess(log.time, log.select({"force", "current", "velocity"}), o);
  REQUIRE(r.segments.size() == 1);
  CHECK(r.gaps == 0);
  // 29.98 s at 0.02 s: 1500 grid points (1499 logged stamps, the first step is 0.039 s).
  CHECK(r.segments[0].rows() == 1500);
  // Same chain in scipy (/usr/bin/python3): t, F = columns 0 and 2 (x 1000) of the file;
  // g = t[0] + 0.02 * arange(floor((t[-1] - t[0]) / 0.02 + 1e-9) + 1); Fg = np.interp(g, t, F);
  // y = sg.sosfiltfilt(sg.butter(4, 20, fs=50, output='sos'), Fg); off = np.median(y[:25]).
  // The filter rings on the contact edges: the peak rises from 10.147 N to 10.99 N.
  const Eigen::VectorXd force = r.segments[0].data.col(0);
  CHECK(close(r.offsets[0], 0.08955056258754246, 1e-9));
  CHECK(close(force.maxCoeff(), 10.89961295643049, 1e-9));
  Eigen::Index peak = 0;
  (void)force.maxCoeff(&peak);
  CHECK(peak == 197);
  CHECK(close(force[1000], 0.7904135038801359 - 0.08955056258754246, 1e-9));
}

}  // namespace identification_signal_test
