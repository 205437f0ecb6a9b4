//! @file
//! Function bodies of identification/hammerstein_wiener_fit.hpp: included at its end (header-only,
//! the default), or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION
//! (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/identification/hammerstein_wiener_fit.hpp"

namespace endohaptics::identification {

ENDOHAPTICS_DECL Eigen::MatrixXd apply_maps(std::span<const StaticMap> maps,
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

ENDOHAPTICS_DECL Eigen::MatrixXd played_input(const Eigen::MatrixXd& u, double play) {
  Eigen::MatrixXd out = u;
  if (play == 0.0 || u.cols() == 0) return out;
  double z = 0.0;
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    const double v = u(k, 0);
    if (!std::isfinite(v)) continue;
    z = model::play(z, v, play);
    out(k, 0) = z;
  }
  return out;
}

ENDOHAPTICS_DECL Eigen::MatrixXd played_input(const Eigen::MatrixXd& u, double play, double slide,
                                              double viscous) {
  if (slide == play && viscous == 0.0) return played_input(u, play);
  Eigen::MatrixXd out = u;
  if (play == 0.0 || u.cols() == 0) return out;
  if (viscous != 0.0 && u.cols() < 2) {
    ENDOHAPTICS_THROW(Error("played_input: a viscous term needs the velocity as input 1, got " +
                            std::to_string(u.cols()) + " input(s)"));
  }
  double z = 0.0;
  double sliding = 0.0;
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    const double friction = viscous == 0.0 ? 0.0 : viscous * u(k, 1);
    if (!std::isfinite(u(k, 0)) || !std::isfinite(friction)) continue;
    z = model::friction_play(z, sliding, u(k, 0), play, slide, friction);
    out(k, 0) = z;
  }
  return out;
}

ENDOHAPTICS_DECL Eigen::MatrixXd simulate(const HammersteinWienerFit& hw, const Eigen::MatrixXd& u,
                                          const Eigen::VectorXd& x0) {
  return apply_maps(hw.output, simulate(hw.linear, apply_maps(hw.input, u), x0));
}
}  // namespace endohaptics::identification

namespace endohaptics::identification {
namespace detail::hw {

ENDOHAPTICS_DECL double normalised_error(std::span<const DataSet> data,
                                         const std::vector<Matrix>& y_hat) {
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
}  // namespace detail::hw
}  // namespace endohaptics::identification

namespace endohaptics::identification {

ENDOHAPTICS_DECL HammersteinWienerFit
fit_hammerstein_wiener(std::span<const DataSet> data, const HammersteinWienerFitOptions& options) {
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

ENDOHAPTICS_DECL HammersteinWienerFit
fit_hammerstein_wiener(const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                       const HammersteinWienerFitOptions& options) {
  const std::vector<DataSet> data{DataSet{u, y}};
  return fit_hammerstein_wiener(std::span<const DataSet>(data), options);
}

}  // namespace endohaptics::identification
