//! @file
//! endohaptics-replay as a function: a model (file or preset) run on logs as a force estimator
//! would, each log on the model's sample time (s), scored causally (or, asked for, by the
//! output-fitted oracle x0): a request (the command line's settings as a plain struct) -> the
//! resolved settings and one FileComparison per log (workflow/model_comparison.hpp).
//! Configuration time: allocates, throws endohaptics::Error.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/files/model_file.hpp"
#include "endohaptics/workflow/model_comparison.hpp"
#include "endohaptics/workflow/prepared_log.hpp"
#include "endohaptics/workflow/preprocessing.hpp"

namespace endohaptics::workflow {

//! What endohaptics-replay is asked to do. The preprocessing is what the model file records
//! (else none); each override given replaces its field.
struct ReplayRequest {
  std::string model;                        //!< model file (JSON) or "preset:NAME"
  std::vector<std::string> logs;            //!< log files, >= 1
  std::string format = "endowrist-2016";    //!< files::parse_log_format's names
  std::vector<std::string> inputs;          //!< the model's input signals; empty: the model's own
  std::vector<std::string> outputs;         //!< the model's output signals; empty: the model's own
  std::string x0 = "steady";                //!< initial_state_from_string's names
  double warmup = ScoringOptions{}.warmup;  //!< s per segment left out (not oracle)
  std::optional<double> csv_row_time{};     //!< s per row of a CSV without time (--ts)
  std::optional<double> lowpass{};          //!< Hz
  std::optional<int> filter_order{};        //!< Butterworth order
  std::optional<double> offset_window{};    //!< s, for offset start
  std::optional<bool> detrend{};            //!< oracle only
  std::optional<double> max_gap{};          //!< s
  std::optional<Eigen::Index> min_segment{};  //!< samples
  std::optional<std::string> offset{};        //!< output offset mode (oracle only)
  std::optional<std::string> input_offset{};  //!< input offset mode (oracle only)
  bool drop_non_finite = false;               //!< drop rows holding NaN/Inf
};

//! The request resolved and, once run, the scores per log.
struct ReplayReport {
  ReplayRequest request{};                   //!< as given
  files::ModelFile model;                    //!< the model replayed
  std::string name{};                        //!< "preset:NAME" or "model FILE", for messages
  std::vector<std::string> model_inputs{};   //!< the model's input names
  std::vector<std::string> model_outputs{};  //!< the model's output names
  LogSelection selection{};                  //!< format, signals, CSV row time
  Preprocessing preprocessing{};             //!< as used
  bool recorded = false;                     //!< the model file recorded its preprocessing
  ScoringOptions scoring{};                  //!< x0 and warm-up as used
  std::vector<FileComparison> files{};       //!< per log, in order
  double mean_rmse = 0.0;                    //!< over the files, the model's output unit
  double mean_fit = 0.0;                     //!< over the files, %

  //! The score is causal (not the oracle x0).
  [[nodiscard]] bool causal() const { return is_causal(scoring.initial_state); }
};

//! Where run_replay reports progress (each may be empty): `resolved`, once the model is loaded
//! and the settings checked; `prepared`, each log on its grid; `scored`, each log's scores
//! (finite: a non-finite score throws before).
struct ReplayHooks {
  std::function<void(const ReplayReport&)> resolved{};                       //!< settings
  std::function<void(const PreparedLog&)> prepared{};                        //!< per log
  std::function<void(const ReplayReport&, const FileComparison&)> scored{};  //!< per log
};

//! Loads the model, resolves the request (signal names against the model's, the recorded
//! preprocessing with the overrides, x0) and scores the model on every log in order. Throws
//! Error on a bad request (naming the option or the model), unreadable logs, or a score that is
//! not finite (a diverging model: no false success).
[[nodiscard]] ENDOHAPTICS_DECL ReplayReport run_replay(const ReplayRequest& request,
                                                       const ReplayHooks& hooks = {});

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/replay_request.ipp"
#endif
