// The UMN grasper logs (../shared/data/umn-mis-tool-2018) as the observer fits take them, for the
// workflow tests that score a model across the two sessions.
#pragma once

#include <algorithm>
#include <endohaptics/files/umn_mis_2018_log.hpp>
#include <endohaptics/workflow/push_load_observer_fit.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "shared_data.hpp"

namespace endohaptics::test {

//! The run files of one session folder, in name order.
inline std::vector<std::filesystem::path> umn_session_paths(const std::string& folder) {
  std::vector<std::filesystem::path> paths;
  for (const auto& e :
       std::filesystem::directory_iterator(shared_data("umn-mis-tool-2018/" + folder))) {
    paths.push_back(e.path());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

//! Five runs of one session folder spread evenly in name order (frequencies and levels both
//! vary), to keep the sanitized tests short: the current, its command and the motor encoder only
//! (the observers use its increments only); grip torque in mN m as logged.
inline std::vector<workflow::LoadObserverData> umn_session_runs(const std::string& folder) {
  const std::vector<std::filesystem::path> paths = umn_session_paths(folder);
  std::vector<workflow::LoadObserverData> out;
  for (std::size_t i = 0; i < 5 && paths.size() > 1; ++i) {
    const auto log = files::read_umn_mis_2018(paths[(i * (paths.size() - 1) + 2) / 4].string());
    out.push_back({log.signal("current"), log.signal("motor_position"), log.signal("grip_torque"),
                   log.signal("current_command")});
  }
  return out;
}

//! Every run of one session folder in name order, as identify gives them to the observer fits
//! (--format umn-mis-2018 at 1 ms): the encoder angle as the running sum of the reader's
//! backward-difference velocity times 1 ms, the current, its command and the grip torque.
inline std::vector<workflow::LoadObserverData> umn_session_all(const std::string& folder) {
  const std::vector<std::filesystem::path> paths = umn_session_paths(folder);
  std::vector<workflow::LoadObserverData> out;
  for (const auto& path : paths) {
    const auto log = files::read_umn_mis_2018(path.string());
    const Eigen::VectorXd velocity = log.signal("motor_velocity");
    Eigen::VectorXd angle(velocity.size());
    double sum = 0.0;
    for (Eigen::Index k = 0; k < velocity.size(); ++k) {
      sum += velocity[k] * 0.001;
      angle[k] = sum;
    }
    out.push_back(
        {log.signal("current"), angle, log.signal("grip_torque"), log.signal("current_command")});
  }
  return out;
}

}  // namespace endohaptics::test
