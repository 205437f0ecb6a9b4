//! @file
//! Hammerstein-Wiener identification (worksheet 4.2.3, figure 4.1): y = g(G(f(u))) with a
//! dead zone (or saturation) f per input found jointly with the linear block G (grid + golden
//! section search over the breakpoints, subspace refit of G at every candidate, minimising the
//! simulated-output NRMSE) and an optional output saturation g. Units: those of u and y.
//! Configuration time: dynamic sizes, throws Error. See docs/models/subspace.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"
#include "endohaptics/model/stop_operators.hpp"

namespace endohaptics::identification {

// The description of a static map lives in the model layer (model/static_map.hpp), where model
// files and the real-time conversions read it too.
using model::StaticMap;
using model::StaticMapKind;

//! Options of `fit_hammerstein_wiener`.
struct HammersteinWienerFitOptions {
  SubspaceOptions linear;  //!< options of every subspace refit (order 0: automatic each time)
  //! Per input: deadzone (default for every input when empty), saturation or none.
  std::vector<StaticMapKind> input_kind;
  //! Per input, signal units: largest dead-zone half width / breakpoint magnitude searched
  //! (empty or <= 0: half the largest |u_i|). For saturation: the largest limit (default
  //! max |u_i|), the smallest searched is 5 % of it.
  std::vector<double> search_limit;
  bool symmetric = true;           //!< one width per input (lower = -upper); false: both searched
  bool output_saturation = false;  //!< also fit a saturation per output (kept only if it helps)
  int grid_points = 21;            //!< coarse grid over each parameter's range, >= 3
  int refine_iterations = 25;      //!< golden-section steps around the best grid point, >= 0
  int sweeps = 2;                  //!< coordinate-descent passes over the parameters, >= 1
};

//! Result: the linear block, the input and output maps, and the fit on the estimation data.
//! Like SubspaceModel, an aggregate built complete (`fit_hammerstein_wiener`).
struct HammersteinWienerFit {
  SubspaceModel linear;             //!< G, identified from f(u)
  std::vector<StaticMap> input{};   //!< f, one per input
  std::vector<StaticMap> output{};  //!< g, one per output (kind none when not fitted)
  Eigen::VectorXd fit{};            //!< NRMSE fit per output on the estimation data, %
  int evaluations = 0;              //!< subspace refits performed
};

//! u (N x nu) with map i applied to column i. Throws Error when the counts differ.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::MatrixXd apply_maps(std::span<const StaticMap> maps,
                                                          const Eigen::MatrixXd& u);

//! u (N x nu) with column 0 passed through a play (backlash) operator of half width `play` >= 0
//! from z = 0: z_k = min(max(z_{k-1}, u_k0 - play), u_k0 + play) (files::ModelFile::current_play;
//! the bridge's estimation::IdentifiedHammersteinWiener runs the same). u itself when play is 0
//! or u has no column; a non-finite sample passes and leaves z as it was.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::MatrixXd played_input(const Eigen::MatrixXd& u, double play);

//! u with column 0 replaced by model::friction_play of it (stuck within `play`, sliding at `slide`,
//! 0 <= slide <= play, plus the viscous current viscous u_k1), from z = 0 and stuck
//! (files::ModelFile::current_play, current_play_slide, current_play_viscous; the bridge's
//! estimation::IdentifiedHammersteinWiener runs the same). played_input(u, play) when slide == play
//! and viscous == 0; u itself when play is 0 or u has no column; a sample whose current or
//! viscous current (viscous u_k1: a non-finite velocity, or one so large the product overflows)
//! is not finite passes unchanged and leaves the play as it was. The tick refuses such a sample
//! instead (all or nothing, its state kept); a recorded run has no all-or-nothing step, and a NaN
//! here would poison every later sample of a simulation. Throws Error when viscous is not 0 and u
//! has fewer than 2 columns.
[[nodiscard]] ENDOHAPTICS_DECL Eigen::MatrixXd played_input(const Eigen::MatrixXd& u, double play,
                                                            double slide, double viscous);

//! Output (N x ny) of the fitted model from x0 of the linear block: g(G(f(u))).
[[nodiscard]] ENDOHAPTICS_DECL Eigen::MatrixXd simulate(const HammersteinWienerFit& hw,
                                                        const Eigen::MatrixXd& u,
                                                        const Eigen::VectorXd& x0);

namespace detail::hw {

using Matrix = Eigen::MatrixXd;

//! Sum over outputs of ||y_i - yhat_i||^2 / ||y_i - mean y_i||^2, over all data sets.
ENDOHAPTICS_DECL double normalised_error(std::span<const DataSet> data,
                                         const std::vector<Matrix>& y_hat);

//! Refits G for input maps `maps` and returns the normalised simulation error (x0 estimated).
struct Evaluator {
  std::span<const DataSet> data;
  const SubspaceOptions& options;
  int evaluations = 0;

  //! The cost (infinite when identification failed) and the model (empty then).
  struct Result {
    double cost;
    std::optional<SubspaceModel> model;
  };

  Result operator()(const std::vector<StaticMap>& maps) {
    ++evaluations;
    std::vector<DataSet> mapped;
    mapped.reserve(data.size());
    for (const DataSet& d : data) mapped.push_back({apply_maps(maps, d.u), d.y});
    Result r{std::numeric_limits<double>::infinity(), std::nullopt};
#if defined(__cpp_exceptions)
    try {
      r.model.emplace(identify(std::span<const DataSet>(mapped), options));
    } catch (const Error&) {
      return r;  // e.g. a dead zone so wide that an input is all zero: rank deficient
    }
#else
    r.model.emplace(identify(std::span<const DataSet>(mapped), options));
#endif
    std::vector<Matrix> y_hat;
    for (std::size_t e = 0; e < mapped.size(); ++e) {
      y_hat.push_back(simulate(*r.model, mapped[e].u, r.model->initial_states[e]));
    }
    r.cost = normalised_error(data, y_hat);
    if (!std::isfinite(r.cost)) r.cost = std::numeric_limits<double>::infinity();
    return r;
  }
};

//! Minimises cost(x) over [lo, hi]: `grid` points, then golden section around the best one.
template <typename Cost>
double minimise_1d(Cost&& cost, double lo, double hi, int grid, int iterations, double& best_cost) {
  double best_x = lo;
  best_cost = std::numeric_limits<double>::infinity();
  const double step = (hi - lo) / static_cast<double>(grid - 1);
  for (int i = 0; i < grid; ++i) {
    const double x = lo + step * static_cast<double>(i);
    const double c = cost(x);
    if (c < best_cost) {
      best_cost = c;
      best_x = x;
    }
  }
  double a = std::max(lo, best_x - step);
  double b = std::min(hi, best_x + step);
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = b - ratio * (b - a);
  double x2 = a + ratio * (b - a);
  double c1 = iterations > 0 ? cost(x1) : best_cost;
  double c2 = iterations > 0 ? cost(x2) : best_cost;
  for (int i = 0; i < iterations; ++i) {
    if (c1 <= c2) {
      b = x2;
      x2 = x1;
      c2 = c1;
      x1 = b - ratio * (b - a);
      c1 = cost(x1);
    } else {
      a = x1;
      x1 = x2;
      c1 = c2;
      x2 = a + ratio * (b - a);
      c2 = cost(x2);
    }
  }
  if (iterations > 0) {
    if (c1 < best_cost) {
      best_cost = c1;
      best_x = x1;
    }
    if (c2 < best_cost) {
      best_cost = c2;
      best_x = x2;
    }
  }
  return best_x;
}

}  // namespace detail::hw

//! Fits f (per input), G and optionally g (per output) to one or several experiments.
//! Coordinate descent: for each searched breakpoint in turn, a grid over its range then golden
//! section, each candidate a full subspace refit of G on f(u) scored by the simulated-output
//! error with x0 estimated; `sweeps` passes. Throws Error on bad options or data (as identify).
[[nodiscard]] ENDOHAPTICS_DECL HammersteinWienerFit fit_hammerstein_wiener(
    std::span<const DataSet> data, const HammersteinWienerFitOptions& options = {});

//! One experiment: u is N x nu, y is N x ny.
[[nodiscard]] ENDOHAPTICS_DECL HammersteinWienerFit
fit_hammerstein_wiener(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                       const HammersteinWienerFitOptions& options = {});

//! The fitted model as the fixed-size real-time HammersteinWiener (model::to_hammerstein_wiener
//! on the fit's linear block and maps): per-channel InputNL (default model::Deadzone; `none`
//! inputs become a zero-width dead zone) and OutputNL (default model::Identity), starting from
//! the linear block's state. Throws Error when sizes differ or a fitted map does not fit the types.
template <int Nx, int Nu, int Ny, typename Scalar = double,
          typename InputNL = model::Deadzone<Scalar>, typename OutputNL = model::Identity<Scalar>>
[[nodiscard]] model::HammersteinWiener<model::StateSpace<Nx, Nu, Ny, Scalar>,
                                       model::PerChannel<InputNL, Nu>,
                                       model::PerChannel<OutputNL, Ny>>
to_hammerstein_wiener(const HammersteinWienerFit& hw) {
  return model::to_hammerstein_wiener<Nx, Nu, Ny, Scalar, InputNL, OutputNL>(hw.linear.state_space,
                                                                             hw.input, hw.output);
}

}  // namespace endohaptics::identification

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/identification/impl/hammerstein_wiener_fit.ipp"
#endif
