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

#include "endohaptics/core/error.hpp"
#include "endohaptics/identification/fit_metrics.hpp"
#include "endohaptics/identification/subspace.hpp"
#include "endohaptics/model/hammerstein_wiener.hpp"
#include "endohaptics/model/state_space.hpp"
#include "endohaptics/model/static_map.hpp"
#include "endohaptics/model/static_nonlinearity.hpp"

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
[[nodiscard]] inline Eigen::MatrixXd apply_maps(std::span<const StaticMap> maps,
                                                const Eigen::MatrixXd& u) {
  if (static_cast<Eigen::Index>(maps.size()) != u.cols()) {
    detail::subspace::fail("apply_maps: " + std::to_string(maps.size()) + " maps for " +
                           std::to_string(u.cols()) + " columns");
  }
  Eigen::MatrixXd out(u.rows(), u.cols());
  for (Eigen::Index j = 0; j < u.cols(); ++j) {
    const StaticMap& map = maps[static_cast<std::size_t>(j)];
    for (Eigen::Index k = 0; k < u.rows(); ++k) out(k, j) = map.apply(u(k, j));
  }
  return out;
}

//! Output (N x ny) of the fitted model from x0 of the linear block: g(G(f(u))).
[[nodiscard]] inline Eigen::MatrixXd simulate(const HammersteinWienerFit& hw,
                                              const Eigen::MatrixXd& u, const Eigen::VectorXd& x0) {
  return apply_maps(hw.output, simulate(hw.linear, apply_maps(hw.input, u), x0));
}

namespace detail::hw {

using Matrix = Eigen::MatrixXd;

//! Sum over outputs of ||y_i - yhat_i||^2 / ||y_i - mean y_i||^2, over all data sets.
inline double normalised_error(std::span<const DataSet> data, const std::vector<Matrix>& y_hat) {
  double cost = 0.0;
  for (std::size_t e = 0; e < data.size(); ++e) {
    const Matrix& y = data[e].y;
    for (Eigen::Index i = 0; i < y.cols(); ++i) {
      const double spread = (y.col(i).array() - y.col(i).mean()).matrix().squaredNorm();
      cost += (y.col(i) - y_hat[e].col(i)).squaredNorm() / std::max(spread, 1e-300);
    }
  }
  return cost;
}

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
[[nodiscard]] inline HammersteinWienerFit fit_hammerstein_wiener(
    std::span<const DataSet> data, const HammersteinWienerFitOptions& options = {}) {
  using detail::subspace::fail;
  using endohaptics::detail::format_number;
  if (data.empty()) fail("fit_hammerstein_wiener: no data sets");
  const Eigen::Index nu = data.front().u.cols();
  const Eigen::Index ny = data.front().y.cols();
  const auto nu_size = static_cast<std::size_t>(std::max<Eigen::Index>(nu, 0));
  if (!options.input_kind.empty() && options.input_kind.size() != nu_size) {
    fail("fit_hammerstein_wiener: input_kind has " + std::to_string(options.input_kind.size()) +
         " entries for " + std::to_string(nu) + " inputs");
  }
  if (!options.search_limit.empty() && options.search_limit.size() != nu_size) {
    fail("fit_hammerstein_wiener: search_limit has " + std::to_string(options.search_limit.size()) +
         " entries for " + std::to_string(nu) + " inputs");
  }
  if (options.grid_points < 3) {
    fail("fit_hammerstein_wiener: grid_points must be >= 3, got " +
         std::to_string(options.grid_points));
  }
  if (options.refine_iterations < 0 || options.sweeps < 1) {
    fail("fit_hammerstein_wiener: refine_iterations must be >= 0 and sweeps >= 1, got " +
         std::to_string(options.refine_iterations) + " and " + std::to_string(options.sweeps));
  }
  // Validates the data once (sizes, finiteness) with the linear options.
  (void)identify(data, options.linear);

  // Search ranges from the data: largest |u_i|, largest u_i and smallest u_i.
  std::vector<double> largest(nu_size, 0.0), top(nu_size, -std::numeric_limits<double>::infinity()),
      bottom(nu_size, std::numeric_limits<double>::infinity());
  for (const DataSet& d : data) {
    for (Eigen::Index j = 0; j < nu; ++j) {
      const auto js = static_cast<std::size_t>(j);
      largest[js] = std::max(largest[js], d.u.col(j).cwiseAbs().maxCoeff());
      top[js] = std::max(top[js], d.u.col(j).maxCoeff());
      bottom[js] = std::min(bottom[js], d.u.col(j).minCoeff());
    }
  }
  std::vector<StaticMap> maps(nu_size);
  for (std::size_t j = 0; j < nu_size; ++j) {
    maps[j].kind = options.input_kind.empty() ? StaticMapKind::deadzone : options.input_kind[j];
    if (maps[j].kind == StaticMapKind::saturation) {  // start without clipping
      maps[j].lower = bottom[j];
      maps[j].upper = top[j];
    }
  }

  detail::hw::Evaluator evaluate{data, options.linear};
  const int grid = options.grid_points;
  const int refine = options.refine_iterations;
  double cost = evaluate(maps).cost;
  for (int sweep = 0; sweep < options.sweeps; ++sweep) {
    for (std::size_t j = 0; j < nu_size; ++j) {
      const double given = options.search_limit.empty() ? 0.0 : options.search_limit[j];
      double best = cost;
      if (maps[j].kind == StaticMapKind::deadzone) {
        const double limit = given > 0.0 ? given : 0.5 * largest[j];
        if (options.symmetric) {
          auto trial = [&](double w) {
            auto m = maps;
            m[j].lower = -w;
            m[j].upper = w;
            return evaluate(m).cost;
          };
          const double w = detail::hw::minimise_1d(trial, 0.0, limit, grid, refine, best);
          if (best < cost) {
            maps[j].lower = -w;
            maps[j].upper = w;
            cost = best;
          }
        } else {
          auto upper_trial = [&](double w) {
            auto m = maps;
            m[j].upper = w;
            return evaluate(m).cost;
          };
          const double up = detail::hw::minimise_1d(upper_trial, 0.0, limit, grid, refine, best);
          if (best < cost) {
            maps[j].upper = up;
            cost = best;
          }
          auto lower_trial = [&](double w) {
            auto m = maps;
            m[j].lower = -w;
            return evaluate(m).cost;
          };
          const double low = detail::hw::minimise_1d(lower_trial, 0.0, limit, grid, refine, best);
          if (best < cost) {
            maps[j].lower = -low;
            cost = best;
          }
        }
      } else if (maps[j].kind == StaticMapKind::saturation) {
        const double limit = given > 0.0 ? given : largest[j];
        auto trial = [&](double l) {
          auto m = maps;
          m[j].lower = -l;
          m[j].upper = l;
          return evaluate(m).cost;
        };
        const double l = detail::hw::minimise_1d(trial, 0.05 * limit, limit, grid, refine, best);
        if (best < cost) {
          maps[j].lower = -l;
          maps[j].upper = l;
          cost = best;
        }
      }
    }
  }

  auto final_eval = evaluate(maps);
  if (!std::isfinite(final_eval.cost)) {
    fail("fit_hammerstein_wiener: no candidate gave a finite simulation error");
  }
  HammersteinWienerFit result{.linear = std::move(*final_eval.model),
                              .input = maps,
                              .output = std::vector<StaticMap>(static_cast<std::size_t>(ny))};

  // Mapped inputs and linear outputs of every data set, for the output maps and the fit.
  std::vector<Eigen::MatrixXd> linear_y;
  for (std::size_t e = 0; e < data.size(); ++e) {
    linear_y.push_back(
        simulate(result.linear, apply_maps(maps, data[e].u), result.linear.initial_states[e]));
  }
  // Output saturation: search the limits on the linear output, then refit B, D, x0 (A, C kept)
  // without the samples the limits clip, which biased them; three rounds.
  constexpr int output_rounds = 3;
  for (int round = 0; options.output_saturation && round < output_rounds; ++round) {
    result.output.assign(static_cast<std::size_t>(ny), StaticMap{});
    for (Eigen::Index i = 0; i < ny; ++i) {
      const auto is = static_cast<std::size_t>(i);
      double hi = -std::numeric_limits<double>::infinity();
      double lo = std::numeric_limits<double>::infinity();
      for (const auto& y : linear_y) {
        hi = std::max(hi, y.col(i).maxCoeff());
        lo = std::min(lo, y.col(i).minCoeff());
      }
      const double span = hi - lo;
      if (!(span > 0.0)) continue;
      auto output_cost = [&](double lower, double upper) {
        StaticMap g{StaticMapKind::saturation, lower, upper};
        double c = 0.0;
        for (std::size_t e = 0; e < data.size(); ++e) {
          const auto& y = data[e].y;
          const double spread = (y.col(i).array() - y.col(i).mean()).matrix().squaredNorm();
          double err = 0.0;
          for (Eigen::Index k = 0; k < y.rows(); ++k) {
            const double d = y(k, i) - g.apply(linear_y[e](k, i));
            err += d * d;
          }
          c += err / std::max(spread, 1e-300);
        }
        return c;
      };
      const double unclipped = output_cost(lo, hi);
      double best = unclipped;
      StaticMap g{StaticMapKind::saturation, lo, hi};
      for (int pass = 0; pass < options.sweeps; ++pass) {
        double c = 0.0;
        const double up = detail::hw::minimise_1d([&](double x) { return output_cost(g.lower, x); },
                                                  lo + 0.5 * span, hi, grid, refine, c);
        if (c < best) {
          best = c;
          g.upper = up;
        }
        const double low =
            detail::hw::minimise_1d([&](double x) { return output_cost(x, g.upper); }, lo,
                                    hi - 0.5 * span, grid, refine, c);
        if (c < best) {
          best = c;
          g.lower = low;
        }
      }
      // Keep the saturation only when it lowers the error by more than 0.1 %.
      if (best < 0.999 * unclipped) result.output[is] = g;
    }
    const bool any =
        std::any_of(result.output.begin(), result.output.end(),
                    [](const StaticMap& g) { return g.kind == StaticMapKind::saturation; });
    if (!any || round + 1 == output_rounds) break;
    std::vector<DataSet> mapped;
    std::vector<Eigen::MatrixXd> weights;
    for (const DataSet& d : data) {
      mapped.push_back({apply_maps(maps, d.u), d.y});
      Eigen::MatrixXd w = Eigen::MatrixXd::Ones(d.y.rows(), ny);
      for (Eigen::Index i = 0; i < ny; ++i) {
        const StaticMap& g = result.output[static_cast<std::size_t>(i)];
        if (g.kind != StaticMapKind::saturation) continue;
        const double margin = 0.02 * (g.upper - g.lower);
        for (Eigen::Index k = 0; k < d.y.rows(); ++k) {
          if (d.y(k, i) >= g.upper - margin || d.y(k, i) <= g.lower + margin) w(k, i) = 0.0;
        }
      }
      weights.push_back(std::move(w));
    }
    const model::DynamicStateSpace<>& G = result.linear.state_space;
    auto refit = detail::subspace::regress_b_d_x0(G.A(), G.C(), std::span<const DataSet>(mapped),
                                                  options.linear.estimate_d,
                                                  options.linear.estimate_x0, &weights);
    model::DynamicStateSpace<> refitted(G.A(), refit.B, G.C(), refit.D, G.sample_time());
    refitted.reset(refit.x0.front());
    result.linear.state_space = std::move(refitted);
    result.linear.initial_states = std::move(refit.x0);
    for (std::size_t e = 0; e < data.size(); ++e) {
      linear_y[e] = simulate(result.linear, mapped[e].u, result.linear.initial_states[e]);
    }
  }
  std::vector<Eigen::MatrixXd> y_hat;
  Eigen::MatrixXd all_y(0, ny);
  Eigen::MatrixXd all_y_hat(0, ny);
  for (std::size_t e = 0; e < data.size(); ++e) {
    const Eigen::MatrixXd yh = apply_maps(result.output, linear_y[e]);
    Eigen::MatrixXd grown_y(all_y.rows() + yh.rows(), ny);
    grown_y << all_y, data[e].y;
    Eigen::MatrixXd grown_y_hat(all_y_hat.rows() + yh.rows(), ny);
    grown_y_hat << all_y_hat, yh;
    all_y.swap(grown_y);
    all_y_hat.swap(grown_y_hat);
  }
  result.fit = nrmse_fit(all_y, all_y_hat);
  result.evaluations = evaluate.evaluations;
  return result;
}

//! One experiment: u is N x nu, y is N x ny.
[[nodiscard]] inline HammersteinWienerFit fit_hammerstein_wiener(
    const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
    const HammersteinWienerFitOptions& options = {}) {
  const std::vector<DataSet> data{DataSet{u, y}};
  return fit_hammerstein_wiener(std::span<const DataSet>(data), options);
}

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
