//! @file
//! Function bodies of workflow/workflow.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/workflow.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL double slowest_time_constant(const model::DynamicStateSpace<>& linear) {
  if (linear.state_size() == 0) return 0.0;
  const double rho = linear.spectral_radius();
  if (!(rho < 1.0)) return std::numeric_limits<double>::infinity();
  if (!(rho > 0.0)) return 0.0;
  return -linear.sample_time() / std::log(rho);
}

ENDOHAPTICS_DECL TimeConstantLimit time_constant_limit(double max_time_constant,
                                                       const std::vector<PreparedLog>& fit_logs) {
  TimeConstantLimit limit{max_time_constant, {}};
  Eigen::Index samples = 0;
  double ts = 0.0;
  for (const PreparedLog& log : fit_logs) {
    for (const DataSet& d : log.segments) {
      if (static_cast<double>(d.y.rows()) * log.sample_time > static_cast<double>(samples) * ts) {
        samples = d.y.rows();
        ts = log.sample_time;
      }
    }
  }
  const double longest = static_cast<double>(samples) * ts;
  if (samples > 0 && longest < limit.seconds) {
    limit = {longest, "the longest segment, " + std::to_string(samples) + " samples of " +
                          detail::format_number(ts) +
                          " s: a slower mode is not identifiable from the logs"};
  }
  return limit;
}

ENDOHAPTICS_DECL std::string refusal(const CandidateModel& c, const TimeConstantLimit& limit) {
  if (c.kind == Method::static_gain) return {};
  if (!(c.spectral_radius < 1.0)) {
    return "unstable (spectral radius " + detail::format_number(c.spectral_radius) + ")";
  }
  if (c.time_constant > limit.seconds) {
    return "near-integrating (slowest time constant " + detail::format_number(c.time_constant) +
           " s > " + detail::format_number(limit.seconds) + " s" +
           (limit.source.empty() ? std::string() : ", " + limit.source) + "; spectral radius " +
           detail::format_number(c.spectral_radius) + ")";
  }
  return {};
}

ENDOHAPTICS_DECL std::string refusal(const CandidateModel& c, double max_time_constant) {
  return refusal(c, TimeConstantLimit{max_time_constant, {}});
}

ENDOHAPTICS_DECL std::size_t best_candidate(const std::vector<CandidateModel>& candidates) {
  if (candidates.empty()) detail::fail("best_candidate: no candidates");
  std::size_t best = candidates.size();
  std::string why;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (!candidates[i].refused.empty()) {
      why += (why.empty() ? "" : "; ") + candidates[i].method + ": " + candidates[i].refused;
      continue;
    }
    if (best == candidates.size() || candidates[i].mean_fit > candidates[best].mean_fit) best = i;
  }
  if (best == candidates.size()) detail::fail("identify: every candidate was refused: " + why);
  return best;
}
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {
namespace detail {

ENDOHAPTICS_DECL double ranking_score(const CandidateModel& c) {
  if (!c.refused.empty() || !std::isfinite(c.mean_fit)) {
    return -std::numeric_limits<double>::infinity();
  }
  return c.mean_fit;
}
}  // namespace detail
}  // namespace endohaptics::workflow

namespace endohaptics::workflow {

ENDOHAPTICS_DECL WorkflowResult identify_logs(const std::vector<PreparedLog>& fit_logs,
                                              const std::vector<PreparedLog>& score_logs,
                                              const std::vector<files::SignalInfo>& inputs,
                                              const std::vector<files::SignalInfo>& outputs,
                                              const WorkflowOptions& options,
                                              const HankelFactor* factor) {
  namespace wf = detail;
  if (fit_logs.empty()) wf::fail("identify: no logs");
  if (score_logs.size() != fit_logs.size()) {
    wf::fail("identify: " + std::to_string(fit_logs.size()) + " logs to fit but " +
             std::to_string(score_logs.size()) + " to score");
  }
  const auto nu = inputs.size();
  std::vector<DataSet> data;
  std::vector<std::string> files;
  for (const PreparedLog& log : fit_logs) {
    files.push_back(log.source);
    for (const DataSet& d : log.segments) data.push_back(d);
  }
  if (data.empty()) wf::fail("identify: the logs have no usable segments");
  const double ts = fit_logs.front().sample_time;
  std::vector<DeadzoneSetting> dz = options.deadzone;
  if (dz.empty()) dz.assign(nu, DeadzoneSetting{});
  if (dz.size() != nu) {
    wf::fail("identify: " + std::to_string(dz.size()) + " dead-zone settings for " +
             std::to_string(nu) + " inputs");
  }
  const bool any_fit = std::any_of(dz.begin(), dz.end(), [](const DeadzoneSetting& s) {
    return s.mode == DeadzoneSetting::Mode::fit;
  });
  const bool any_map = std::any_of(dz.begin(), dz.end(), [](const DeadzoneSetting& s) {
    return s.mode != DeadzoneSetting::Mode::none;
  });
  if (options.deadzone_grid < 2 || options.deadzone_refine < 0) {
    wf::fail("identify: the dead-zone search needs >= 2 grid points and >= 0 refinements");
  }
  // Search range of each fitted dead zone: [0, half the largest |u_j|] (4.2.3 friction is well
  // inside it).
  std::vector<double> limit(nu, 0.0);
  for (const DataSet& d : data) {
    for (std::size_t j = 0; j < nu; ++j) {
      limit[j] =
          std::max(limit[j], 0.5 * d.u.col(static_cast<Eigen::Index>(j)).cwiseAbs().maxCoeff());
    }
  }

  if (!(options.max_time_constant > 0.0)) {
    wf::fail("identify: max_time_constant must be > 0 s (infinity: no limit), got " +
             wf::format_number(options.max_time_constant));
  }
  const TimeConstantLimit tc_limit = time_constant_limit(options.max_time_constant, fit_logs);
  WorkflowResult result;
  SubspaceOptions so;
  so.order = options.order;
  so.max_order = options.max_order;
  so.block_rows = options.block_rows;
  so.sample_time = ts;

  const auto maps_for = [&](const std::vector<double>& widths) {
    std::vector<StaticMap> maps(nu);
    for (std::size_t j = 0; j < nu; ++j) {
      if (dz[j].mode == DeadzoneSetting::Mode::none) continue;
      const double w = dz[j].mode == DeadzoneSetting::Mode::fixed ? dz[j].width : widths[j];
      maps[j] = {StaticMapKind::deadzone, -w, w};
    }
    return maps;
  };
  // The block-Hankel factor of the data under each dead-zone setting (the maps' breakpoints):
  // the fit of another order or weighting on the same mapped data reuses it.
  std::vector<std::pair<std::vector<double>, HankelFactor>> factors;
  const auto key_of = [](const std::vector<StaticMap>& maps) {
    std::vector<double> key;
    for (const StaticMap& m : maps)
      key.insert(key.end(), {static_cast<double>(m.kind), m.lower, m.upper});
    return key;
  };
  if (factor != nullptr)
    factors.emplace_back(key_of(maps_for(std::vector<double>(nu, 0.0))), *factor);
  const auto factor_for = [&](const std::vector<StaticMap>& maps) -> HankelFactor& {
    std::vector<double> key = key_of(maps);
    for (auto& [k, f] : factors) {
      if (k == key) return f;
    }
    return factors.emplace_back(std::move(key), HankelFactor{}).second;
  };
  // Fits the linear block on the mapped data and scores the candidate causally.
  const auto evaluate = [&](Method kind, const SubspaceOptions& opts,
                            const std::vector<StaticMap>& maps) {
    ++result.evaluations;
    const std::string method(to_string(kind));
    std::vector<DataSet> mapped;
    mapped.reserve(data.size());
    for (const DataSet& d : data) mapped.push_back({apply_maps(maps, d.u), d.y});
    SubspaceModel linear = kind == Method::static_gain
                               ? fit_static_gain(std::span<const DataSet>(mapped), ts)
                               : identify(std::span<const DataSet>(mapped), opts, factor_for(maps));
    files::ModelProvenance p;
    p.method = method;
    p.files = files;
    CandidateModel c{.method = method,
                     .kind = kind,
                     .model = files::make_model_file(linear, inputs, outputs, p),
                     .linear = std::move(linear)};
    if (any_map) {
      c.model.input_nonlinearity = maps;
      c.model.output_nonlinearity.assign(outputs.size(), StaticMap{});
    }
    c.spectral_radius = c.linear.state_space.spectral_radius();
    c.time_constant = slowest_time_constant(c.model.state_space);
    c.refused = refusal(c, tc_limit);
    double sum = 0.0;
    std::vector<double> per_output(outputs.size(), 0.0);
    for (const PreparedLog& log : score_logs) {
      c.files.push_back(compare_log(c.model, log, options.scoring));
      sum += c.files.back().mean_fit();
      for (std::size_t i = 0; i < outputs.size(); ++i) {
        per_output[i] += c.files.back().fit[static_cast<Eigen::Index>(i)] /
                         static_cast<double>(score_logs.size());
      }
    }
    c.mean_fit = sum / static_cast<double>(score_logs.size());
    c.model.provenance.fit_percent = per_output;
    if (options.progress) {
      std::string line = "model " + std::to_string(result.evaluations) + ": " + method;
      if (kind != Method::static_gain) line += ", order " + std::to_string(c.linear.order);
      std::array<char, 64> buffer{};
      for (std::size_t j = 0; j < maps.size(); ++j) {
        if (maps[j].kind == StaticMapKind::deadzone) {
          std::snprintf(buffer.data(), buffer.size(), "%.4g", maps[j].upper);
          line += ", dead zone " + inputs[j].name + " " + buffer.data();
        }
      }
      std::snprintf(buffer.data(), buffer.size(), "%.2f", c.mean_fit);
      line += std::string(": mean causal fit ") + buffer.data() + " %" +
              (c.refused.empty() ? std::string() : " (refused)");
      options.progress(line);
    }
    return c;
  };
  // One candidate, or none when its fit fails (e.g. dead zones that leave the subspace fit an
  // unstable model whose B, D, x0 regression overflows): the search goes on without it, and the
  // last failure is kept for the message if no candidate fits at all.
  std::string last_failure;
  const auto try_evaluate =
      [&](Method method, const SubspaceOptions& opts,
          const std::vector<StaticMap>& maps) -> std::optional<CandidateModel> {
#if defined(__cpp_exceptions)
    try {
      return evaluate(method, opts, maps);
    } catch (const Error& e) {
      last_failure = e.what();
      return std::nullopt;
    }
#else
    return evaluate(method, opts, maps);
#endif
  };
  // The best dead zones for one method: a grid over each fitted input's range, then golden-
  // section steps around the best grid point; one input after the other (coordinate search).
  const auto search_deadzones = [&](Method method, const SubspaceOptions& opts) {
    std::vector<double> widths(nu, 0.0);
    std::optional<CandidateModel> best = try_evaluate(method, opts, maps_for(widths));
    if (!any_fit) {
      if (!best) wf::fail(last_failure);
      return std::move(*best);
    }
    for (std::size_t j = 0; j < nu; ++j) {
      if (dz[j].mode != DeadzoneSetting::Mode::fit || !(limit[j] > 0.0)) continue;
      const auto try_width = [&](double w) {
        std::vector<double> trial = widths;
        trial[j] = w;
        std::optional<CandidateModel> c = try_evaluate(method, opts, maps_for(trial));
        if (!c) return -std::numeric_limits<double>::infinity();
        const double score = wf::ranking_score(*c);
        if (!best || score > wf::ranking_score(*best)) {
          best = std::move(c);
          widths = trial;
        }
        return score;
      };
      const int n = options.deadzone_grid;
      const double step = limit[j] / static_cast<double>(n - 1);
      for (int g = 1; g < n; ++g) try_width(step * g);  // g = 0 is the start point
      // Golden section on [best - step, best + step], scoring each probe.
      double a = std::max(0.0, widths[j] - step);
      double b = std::min(limit[j], widths[j] + step);
      constexpr double r = 0.6180339887498949;
      for (int k = 0; k < options.deadzone_refine && b - a > 1e-12; ++k) {
        const double x1 = b - r * (b - a);
        const double x2 = a + r * (b - a);
        const double f1 = try_width(x1);
        const double f2 = try_width(x2);
        if (f1 >= f2) {
          b = x2;
        } else {
          a = x1;
        }
      }
    }
    if (!best) wf::fail(last_failure);
    best->method += " + dead zone";
    return std::move(*best);
  };

  if (options.candidates.empty() && !options.static_gain) {
    wf::fail("identify: no subspace method to try");
  }
  const std::size_t tries = options.candidates.size() + (options.static_gain ? 1 : 0);
  for (const Weighting w : options.candidates) {
    so.weighting = w;
    const std::string method(to_string(w));
    // One of several weightings may fail (e.g. a model so unstable that the B, D, x0
    // regression overflows): record it and go on with the others.
    const auto attempt = [&] { result.candidates.push_back(search_deadzones(method_of(w), so)); };
#if defined(__cpp_exceptions)
    if (tries > 1) {
      try {
        attempt();
      } catch (const Error& e) {
        result.failures.push_back(method + ": " + e.what());
      }
      continue;
    }
#endif
    wf::with_context(method, attempt);
  }
  const std::size_t subspace_candidates = result.candidates.size();
  // Order search: the best subspace method and dead zone at every order, ranked by the causal
  // score; the smallest order within options.order_tolerance of the best admissible score
  // replaces that candidate (parsimony: a higher order must earn its states). Also when that
  // candidate was refused: another order may be admissible.
  if (subspace_candidates > 0 && options.order == 0 && options.search_order) {
    std::size_t top = 0;
    for (std::size_t i = 1; i < subspace_candidates; ++i) {
      if (wf::ranking_score(result.candidates[i]) > wf::ranking_score(result.candidates[top]))
        top = i;
    }
    CandidateModel& base = result.candidates[top];
    SubspaceOptions opts = so;
    opts.weighting = base.linear.weighting;
    const std::vector<StaticMap> maps = base.model.input_nonlinearity.empty()
                                            ? std::vector<StaticMap>(nu)
                                            : base.model.input_nonlinearity;
    std::vector<CandidateModel> by_order;
    for (int n = 1; n <= options.max_order; ++n) {
      if (n == base.linear.order) {
        result.order_search.push_back({n, base.mean_fit, base.spectral_radius, base.refused});
        by_order.push_back(base);
        continue;
      }
      opts.order = n;
#if defined(__cpp_exceptions)
      try {
#endif
        CandidateModel c = evaluate(base.kind, opts, maps);
        c.method = base.method;  // keeps " + dead zone" when the base has one
        c.model.provenance.method = base.method;
        result.order_search.push_back({n, c.mean_fit, c.spectral_radius, c.refused});
        by_order.push_back(std::move(c));
#if defined(__cpp_exceptions)
      } catch (const Error& e) {
        result.order_search.push_back(
            {n, -std::numeric_limits<double>::infinity(), 0.0, std::string("failed: ") + e.what()});
      }
#endif
    }
    double best_score = -std::numeric_limits<double>::infinity();
    for (const CandidateModel& c : by_order) {
      best_score = std::max(best_score, wf::ranking_score(c));
    }
    if (std::isfinite(best_score)) {        // else: every order refused, base stays (refused)
      for (CandidateModel& c : by_order) {  // in increasing order
        if (wf::ranking_score(c) < best_score - options.order_tolerance) continue;
        if (c.linear.order != base.linear.order) {
          c.order_searched = true;
          base = std::move(c);
        }
        break;
      }
    }
  }
  // The static baseline as a candidate of its own (with the same dead-zone search).
  if (options.static_gain) {
    const auto attempt = [&] {
      result.candidates.push_back(search_deadzones(Method::static_gain, so));
    };
#if defined(__cpp_exceptions)
    if (tries > 1) {
      try {
        attempt();
      } catch (const Error& e) {
        result.failures.push_back(std::string("static: ") + e.what());
      }
    } else {
      attempt();
    }
#else
    attempt();
#endif
  }
  if (result.candidates.empty()) {
    std::string all;
    for (const auto& f : result.failures) all += (all.empty() ? "" : "; ") + f;
    wf::fail("identify: every method failed: " + all);
  }
  result.best = best_candidate(result.candidates);
  return result;
}

}  // namespace endohaptics::workflow

namespace endohaptics::workflow {

ENDOHAPTICS_DECL ModelChoice choose_family(
    const WorkflowResult* subspace, const std::vector<files::ModelKind>& joint_kinds,
    const std::vector<PreparedLog>& fit_logs, const std::vector<PreparedLog>& score_logs,
    const std::vector<PreparedLog>& joint_logs, const std::vector<files::SignalInfo>& inputs,
    const std::vector<files::SignalInfo>& outputs, const WorkflowOptions& options) {
  namespace wf = detail;
  const std::size_t families = (subspace != nullptr ? 1 : 0) + joint_kinds.size();
  if (families == 0) wf::fail("identify: no model family to fit");
  const std::size_t n_files = !joint_logs.empty() ? joint_logs.size() : score_logs.size();
  if (!joint_kinds.empty() && joint_logs.size() != n_files) {
    wf::fail("choose_family: the joint-model logs differ in number from the others");
  }
  if (subspace != nullptr && (fit_logs.size() != score_logs.size() ||
                              (!joint_kinds.empty() && score_logs.size() != n_files))) {
    wf::fail("choose_family: the subspace logs differ in number from the others");
  }
  // The subspace family refitted with its structure fixed (method, order, dead zones).
  WorkflowOptions fixed = options;
  std::string subspace_name;
  if (subspace != nullptr) {
    const CandidateModel& c = subspace->chosen();
    subspace_name = c.method;
    fixed.candidates.clear();
    fixed.static_gain = c.kind == Method::static_gain;
    if (!fixed.static_gain) fixed.candidates = {c.linear.weighting};
    fixed.order = fixed.static_gain ? 0 : c.linear.order;
    fixed.search_order = false;
    fixed.progress = {};  // the folds report once each (below), not their one fit
    fixed.deadzone.assign(inputs.size(), DeadzoneSetting{});
    for (std::size_t j = 0; j < c.model.input_nonlinearity.size() && j < inputs.size(); ++j) {
      const StaticMap& m = c.model.input_nonlinearity[j];
      if (m.kind == StaticMapKind::deadzone) {
        fixed.deadzone[j] = {DeadzoneSetting::Mode::fixed, m.upper};
      }
    }
  }
  // The subspace family's block-Hankel factor per training file, with the chosen dead zones and
  // the chosen model's scaling: each fold combines those of its files instead of a pass over its
  // data (filled on the first fold; left empty when a file cannot carry the horizon alone).
  std::vector<HankelFactor> file_factors;
  bool file_factors_tried = false;
  const auto make_file_factors = [&] {
    file_factors_tried = true;
    const SubspaceModel& linear = subspace->chosen().linear;
    std::vector<StaticMap> maps(inputs.size());
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      if (fixed.deadzone[j].mode == DeadzoneSetting::Mode::fixed) {
        maps[j] = {StaticMapKind::deadzone, -fixed.deadzone[j].width, fixed.deadzone[j].width};
      }
    }
    Eigen::Index samples = 0;
    int sets = 0;
    for (const PreparedLog& log : fit_logs) {
      for (const DataSet& d : log.segments) samples += d.u.rows();
      sets += static_cast<int>(log.segments.size());
    }
    const int s = fixed.block_rows > 0
                      ? fixed.block_rows
                      : default_block_rows(samples, sets, static_cast<int>(inputs.size()),
                                           static_cast<int>(outputs.size()), fixed.order);
    if (s == 0 || linear.input_scale.size() != static_cast<Eigen::Index>(inputs.size())) return;
#if defined(__cpp_exceptions)
    try {
#endif
      for (const PreparedLog& log : fit_logs) {
        std::vector<DataSet> mapped;
        for (const DataSet& d : log.segments) mapped.push_back({apply_maps(maps, d.u), d.y});
        file_factors.push_back(hankel_factor(std::span<const DataSet>(mapped), s,
                                             linear.input_scale, linear.output_scale));
      }
#if defined(__cpp_exceptions)
    } catch (const Error&) {
      file_factors.clear();  // e.g. a segment shorter than 2 s: each fold computes its own
    }
#endif
  };
  // Each joint family's constants, chosen once on all training files (on first use) and held
  // in its fold refits and its final fit; a search that fails fails every fold the same way.
  std::vector<std::optional<JointConstants>> joint_constants(joint_kinds.size());
  std::vector<std::string> constants_failure(joint_kinds.size());
  std::size_t constant_searches = 0;
  const auto constants_of = [&](std::size_t k) -> const JointConstants& {
    if (!joint_constants[k] && constants_failure[k].empty()) {
#if defined(__cpp_exceptions)
      try {
#endif
        joint_constants[k] = choose_joint_constants(joint_kinds[k], joint_logs, inputs, outputs,
                                                    options.scoring.warmup);
        if (joint_kinds[k] != files::ModelKind::push_load_observer) ++constant_searches;
#if defined(__cpp_exceptions)
      } catch (const Error& e) {
        constants_failure[k] = e.what();
      }
#endif
      if (joint_constants[k] && options.progress &&
          joint_kinds[k] != files::ModelKind::push_load_observer) {
        options.progress("family " + std::string(files::to_string(joint_kinds[k])) +
                         ": constants chosen on all " + std::to_string(n_files) +
                         " training files, held in the folds' refits");
      }
    }
    if (!joint_constants[k]) wf::fail(constants_failure[k]);
    return *joint_constants[k];
  };
  const auto fit_family = [&](std::size_t family,
                              const std::vector<std::size_t>& train) -> files::ModelFile {
    if (subspace != nullptr && family == 0) {
      std::vector<PreparedLog> f, s;
      for (const std::size_t i : train) {
        f.push_back(fit_logs[i]);
        s.push_back(score_logs[i]);
      }
      if (!fixed.static_gain && !file_factors_tried) make_file_factors();
      if (file_factors.size() == fit_logs.size()) {
        std::vector<HankelFactor> parts;
        for (const std::size_t i : train) parts.push_back(file_factors[i]);
        const HankelFactor combined = combine(std::span<const HankelFactor>(parts));
        return identify_logs(f, s, inputs, outputs, fixed, &combined).chosen().model;
      }
      return identify_logs(f, s, inputs, outputs, fixed).chosen().model;
    }
    // The constants first (held unless nested): their search on all files runs before the
    // fold's copy is made.
    const std::size_t k = family - (subspace != nullptr ? 1 : 0);
    const JointConstants* constants = options.nested_joint_constants ? nullptr : &constants_of(k);
    std::vector<PreparedLog> j;
    for (const std::size_t i : train) j.push_back(joint_logs[i]);
    JointModelFit fit =
        fit_joint_model(joint_kinds[k], j, inputs, outputs, options.scoring.warmup, constants);
    constant_searches += fit.constant_searches;
    return std::move(fit.model);
  };
  const auto logs_of = [&](std::size_t family) -> const std::vector<PreparedLog>& {
    return subspace != nullptr && family == 0 ? score_logs : joint_logs;
  };
  // The scores first; the ModelChoice is made with the chosen family's model at the end.
  std::vector<FamilyScore> scores(families);
  for (std::size_t f = 0; f < families; ++f) {
    scores[f].family =
        subspace != nullptr && f == 0
            ? subspace_name
            : std::string(files::to_string(joint_kinds[f - (subspace != nullptr ? 1 : 0)]));
  }
  std::vector<std::vector<std::size_t>> inner;
  if (families > 1) inner = inner_folds(n_files);
  // One training file and several families: no file to hold out, so each family is fitted and
  // scored on that file (the training score; stated in the report by an empty `folds`).
  const bool training_only = families > 1 && inner.empty();
  const std::vector<std::vector<std::size_t>> all_files{{0}};
  const auto& folds = training_only ? all_files : inner;
  for (std::size_t f = 0; f < families && !folds.empty(); ++f) {
    FamilyScore& score = scores[f];
    double fit_sum = 0.0, rmse_sum = 0.0;
    for (const auto& held_out : folds) {
      std::vector<std::size_t> train;
      for (std::size_t i = 0; i < n_files; ++i) {
        if (training_only || std::find(held_out.begin(), held_out.end(), i) == held_out.end()) {
          train.push_back(i);
        }
      }
      double fold_fit = 0.0, fold_rmse = 0.0;
#if defined(__cpp_exceptions)
      try {
#endif
        const files::ModelFile m = fit_family(f, train);
        for (const std::size_t i : held_out) {
          const FileComparison c = compare_log(m, logs_of(f)[i], options.scoring);
          fold_fit += c.mean_fit() / static_cast<double>(held_out.size());
          fold_rmse += c.mean_rmse() / static_cast<double>(held_out.size());
        }
#if defined(__cpp_exceptions)
      } catch (const Error& e) {
        score.failure = e.what();
        fold_fit = -std::numeric_limits<double>::infinity();
        fold_rmse = std::numeric_limits<double>::infinity();
      }
#endif
      score.fold_fit.push_back(fold_fit);
      score.fold_rmse.push_back(fold_rmse);
      if (options.progress) {
        std::array<char, 64> buffer{};
        std::snprintf(buffer.data(), buffer.size(), "%.2f", fold_fit);
        options.progress("family " + score.family + ", fold " +
                         std::to_string(score.fold_fit.size()) + " of " +
                         std::to_string(folds.size()) + ": causal fit " + buffer.data() + " %");
      }
      fit_sum += fold_fit;
      rmse_sum += fold_rmse;
    }
    const auto k = static_cast<double>(folds.size());
    score.mean_fit =
        std::isfinite(fit_sum) ? fit_sum / k : -std::numeric_limits<double>::infinity();
    score.mean_rmse = rmse_sum / k;
    if (!std::isfinite(score.mean_fit)) score.mean_fit = -std::numeric_limits<double>::infinity();
  }
  std::size_t best = 0;
  for (std::size_t f = 1; f < families; ++f) {
    if (scores[f].mean_fit > scores[best].mean_fit) best = f;
  }
  if (subspace != nullptr && best == 0) {
    return ModelChoice{.model = subspace->chosen().model,
                       .family = scores[best].family,
                       .families = std::move(scores),
                       .best = best,
                       .folds = std::move(inner),
                       .files = subspace->chosen().files,
                       .constant_searches = constant_searches};
  }
  const std::size_t joint = best - (subspace != nullptr ? 1 : 0);
  JointModelFit fit = fit_joint_model(joint_kinds[joint], joint_logs, inputs, outputs,
                                      options.scoring.warmup, &constants_of(joint));
  constant_searches += fit.constant_searches;
  ModelChoice choice{.model = std::move(fit.model),
                     .family = scores[best].family,
                     .families = std::move(scores),
                     .best = best,
                     .folds = std::move(inner),
                     .joint_summary = std::move(fit.summary),
                     .constant_searches = constant_searches};
  for (const PreparedLog& log : joint_logs) {
    choice.files.push_back(compare_log(choice.model, log, options.scoring));
  }
  double sum = 0.0;
  for (const FileComparison& c : choice.files) sum += c.mean_fit();
  choice.model.provenance.fit_percent = {sum / static_cast<double>(choice.files.size())};
  return choice;
}

}  // namespace endohaptics::workflow
