// endohaptics-bridge: the program between the operator's stylus and the sbRIO. Wires a UDP
// transport, a haptic device (a scripted operator, or a Geomagic Touch through OpenHaptics), the
// 2016 force estimator and the cylindrical mapping into a TeleopLoop, then prints table-3.1
// figures. SIGINT/SIGTERM: zero force, motors disabled, final statistics, exit 0. The link and
// the loop are shared with endohaptics-ros-bridge (link_options.hpp, bridge_app.hpp).
#include <endohaptics/sim/haptic_device_model.hpp>
#include <endohaptics/sim/scripted_operator.hpp>
#include <endohaptics/sim/simulated_rig.hpp>

#include "bridge_app.hpp"
#ifdef ENDOHAPTICS_HAVE_OPENHAPTICS
#include "openhaptics_device.hpp"
#endif

namespace files = endohaptics::files;

int main(int argc, char** argv) {
  bridge::Options opt;
  const examples::Parsed parsed = bridge::parse_options(argc, argv, opt);
  if (parsed.exit_code) return *parsed.exit_code;

  try {
    if (bridge::check_options(parsed, opt)) return 0;
    bridge::stop_on_signals();
    const files::BridgeConfig cfg = bridge::load_config(opt);
    endohaptics::SteadyClock clock;
    if (opt.device == "sim") {
      endohaptics::sim::ScriptedOperator<endohaptics::SteadyClock> device(clock,
                                                                          cfg.operator_script);
      return bridge::run_bridge(device, clock, opt, cfg);
    }
    if (opt.device == "arm-model") {
      // From the rest pose straight in along -x (closing the clamps, eq. 5.9) to 25 mm of stylus
      // beyond where clamp 1 meets the emulator's default contact, then hold.
      const auto rig =
          endohaptics::sim::endowrist_2016_rig<4>(endohaptics::sim::Environment::tissue);
      const auto& contact = rig.joints[2].contact;
      const auto& m = cfg.mapping;
      const double target = std::clamp(
          contact.contact_position + contact.direction * m.a_clamp * 0.025, m.lower[2], m.upper[2]);
      endohaptics::sim::PressScript script;
      script.start = endohaptics::kinematics::rest_position<double>(m);
      script.travel = Eigen::Vector3d((m.b_clamp - target) / m.a_clamp - script.start.x(), 0, 0);
      endohaptics::sim::HapticDeviceModel<endohaptics::SteadyClock> device(clock, script);
      return bridge::run_bridge(device, clock, opt, cfg);
    }
#ifdef ENDOHAPTICS_HAVE_OPENHAPTICS
    bridge::OpenHapticsDevice device;
    return bridge::run_bridge(device, clock, opt, cfg);
#else
    fmt::print(stderr,
               "error: this bridge was built without the OpenHaptics SDK (--device openhaptics); "
               "see docs/rig.md\n");
    return 2;
#endif
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
