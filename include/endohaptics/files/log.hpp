//! @file
//! A log as the readers return it: named signals (with units) sampled at strictly increasing
//! time stamps (s), plus the LogReport of what the reader dropped or repaired. Looking up an
//! unknown signal throws endohaptics::Error naming the file and the signals it has.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "endohaptics/core/error.hpp"
#include "endohaptics/files/log_report.hpp"

namespace endohaptics::files {

//! A log: named signals sampled at `time`, plus the report of what was dropped or repaired.
struct Log {
  std::string source;              //!< the file read
  std::vector<std::string> names;  //!< one per column of `data` ("time" is not a column)
  std::vector<std::string> units;  //!< one per column ("" when unknown)
  Eigen::VectorXd time;            //!< s, strictly increasing (rebased: starts at 0)
  Eigen::MatrixXd data;            //!< rows: samples, columns: signals in `names` order
  LogReport report;                //!< what the reader dropped, repaired, found
  //! `key=value` pairs of the file's header, in file order (formats that have them)
  std::vector<std::pair<std::string, std::string>> metadata;

  //! Number of samples (rows of `data`, entries of `time`).
  [[nodiscard]] Eigen::Index rows() const noexcept { return time.size(); }

  //! True for "time" and for every name in `names`.
  [[nodiscard]] bool has(std::string_view name) const {
    return name == "time" || std::find(names.begin(), names.end(), name) != names.end();
  }

  //! Column of `name` in `data`. Throws Error naming the file and the available signals.
  [[nodiscard]] Eigen::Index column(std::string_view name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
      std::string known = "time";
      for (const auto& n : names) known += ", " + n;
      ENDOHAPTICS_THROW(Error("Log: " + source + ": no signal named '" + std::string(name) +
                              "' (signals: " + known + ")"));
    }
    return static_cast<Eigen::Index>(it - names.begin());
  }

  //! The samples of one signal ("time" gives `time`). Throws Error for an unknown name.
  [[nodiscard]] Eigen::VectorXd signal(std::string_view name) const {
    if (name == "time") return time;
    return data.col(column(name));
  }

  //! The named signals as columns, in the order given. Throws Error for an unknown name.
  [[nodiscard]] Eigen::MatrixXd select(const std::vector<std::string>& selected) const {
    Eigen::MatrixXd out(rows(), static_cast<Eigen::Index>(selected.size()));
    for (std::size_t i = 0; i < selected.size(); ++i) {
      out.col(static_cast<Eigen::Index>(i)) = signal(selected[i]);
    }
    return out;
  }
};

}  // namespace endohaptics::files
