//! @file
//! Function bodies of files/clamp_model_file.hpp: included at its end (header-only, the default),
//! or compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/clamp_model_file.hpp"

namespace endohaptics::files {

ENDOHAPTICS_DECL estimation::BridgeJointModel bridge_joint_model(const ModelFile& file,
                                                                 const std::string& where) {
  using estimation::BridgeJointModel;
  const auto joint_model = [&] {
    if (file.current_reference) {
      ENDOHAPTICS_THROW(Error(  // with_context below adds the file's name
          "the " + std::string(to_string(file.kind())) +
          " refers its current to the commanded current (a third input), which the sbRIO "
          "protocol does not carry: identify the bridge's model from the current and the "
          "velocity only"));
    }
    return std::visit(
        [](const auto& p) {
          using P = std::decay_t<decltype(p)>;
          if constexpr (std::is_same_v<P, estimation::StallHoldParameters<double>>) {
            return BridgeJointModel(estimation::StallHold<double>(p));
          } else if constexpr (std::is_same_v<P, estimation::PushLoadObserverParameters<double>>) {
            return BridgeJointModel(estimation::PushLoadObserver<double>(p));
          } else if constexpr (std::is_same_v<
                                   P, estimation::BidirectionalLoadObserverParameters<double>>) {
            return BridgeJointModel(estimation::BidirectionalLoadObserver<double>(p));
          } else {
            return BridgeJointModel(estimation::models_2016<double>().clamp1);  // not reached
          }
        },
        file.parameters);
  };
  // The clamp type holds 6 states (the 2016 yaw model's): a linear block of lower order runs
  // in it embedded exactly (model::embed_states: the added states are decoupled and zero).
  const auto hammerstein_wiener = [&] {
    // An unstable linear block loads as a valid model, but its estimate would grow until the
    // tick rejects it as non-finite (and renders no force): refused here, as identify does.
    const double rho = file.state_space.spectral_radius();
    if (!(rho < 1.0)) {
      ENDOHAPTICS_THROW(Error(where + ": the clamp model is not stable (spectral radius " +
                              endohaptics::detail::format_number(rho) +
                              ", must be < 1): its estimate would grow without bound"));
    }
    // A force model maps A and rad/s to N: every number of it lies within the bound of every
    // joint-model parameter (model::max_joint_model_parameter); a larger one (a corrupt or
    // hostile file, C = 1e308) would pin the estimate at its output limit on every tick.
    const model::DynamicStateSpace<>& ss = file.state_space;
    const std::pair<const char*, const Eigen::MatrixXd*> blocks[] = {
        {"A", &ss.A()}, {"B", &ss.B()}, {"C", &ss.C()}, {"D", &ss.D()}};
    const double bound = model::max_joint_model_parameter;
    for (const auto& [name, block] : blocks) {
      for (Eigen::Index r = 0; r < block->rows(); ++r) {
        for (Eigen::Index c = 0; c < block->cols(); ++c) {
          if (!(std::fabs((*block)(r, c)) <= bound)) {
            ENDOHAPTICS_THROW(
                Error(where + ": " + name + "[" + std::to_string(r) + "][" + std::to_string(c) +
                      "] is " + endohaptics::detail::format_number((*block)(r, c)) +
                      ": a clamp force model's numbers must lie in [-1e6, 1e6] (A, rad/s -> N)"));
          }
        }
      }
    }
    if (!(ss.state().cwiseAbs().maxCoeff() <= bound)) {
      ENDOHAPTICS_THROW(Error(where + ": x0 holds a value beyond 1e6: a clamp force model's "
                                      "numbers must lie in [-1e6, 1e6]"));
    }
    ModelFile six = file;
    if (six.state_space.state_size() < estimation::bridge_clamp_states) {
      six.state_space = model::embed_states(six.state_space, estimation::bridge_clamp_states);
    }
    return BridgeJointModel(estimation::IdentifiedHammersteinWiener<double>(
        hammerstein_wiener_from<estimation::bridge_clamp_states, 2, 1>(six, where),
        model::FreeMotionThreshold<double>(file.free_motion_threshold), file.current_play,
        file.current_play_slide, file.current_play_viscous));
  };
  return file.is_joint_model() ? detail::model_file::with_context(where, joint_model)
                               : hammerstein_wiener();
}

ENDOHAPTICS_DECL estimation::BridgeJointModel load_bridge_joint_model(
    const std::filesystem::path& path) {
  return bridge_joint_model(load_model(path), "model file " + path.string());
}

}  // namespace endohaptics::files
