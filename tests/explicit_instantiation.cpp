// Instantiates every member of every class template, so an unused member cannot hide an error.
// One argument list per template (plus float where the template takes a scalar): every distinct
// size instantiates Eigen's decompositions again, and this file used to cost over 3 minutes of
// compile time. The tests cover the other sizes.
#include <endohaptics/endohaptics.hpp>

namespace eh = endohaptics;

struct InstantiationDevice {
  eh::teleop::DeviceStatus read(eh::teleop::StylusSample&) noexcept {
    return eh::teleop::DeviceStatus::ok;
  }
  eh::teleop::DeviceStatus command_force(const Eigen::Vector3d&) noexcept {
    return eh::teleop::DeviceStatus::ok;
  }
};

template class eh::protocol::PacketCodec<1>;
template class eh::protocol::PacketCodec<4>;
template struct eh::protocol::MotorState<4>;
template struct eh::protocol::MotorSetpoint<4>;

template class eh::model::StateSpace<3, 2, 1>;
template class eh::model::StateSpace<1, 1, 1, float>;
template class eh::model::ContinuousStateSpace<3, 1, 2>;
// clang 14 instantiates members whose requires-clause is unsatisfied, so only argument lists
// that satisfy every constraint are listed (default-constructible nonlinearities, Nm = Ny).
template class eh::model::HammersteinWiener<eh::model::StateSpace<6, 2, 1>>;
template class eh::model::FrictionModel<1, float>;
template class eh::model::FrictionModel<4>;
template class eh::model::HumanArmModel<double>;
template class eh::model::HumanArmModel<float>;
template class eh::model::HumanArm3<double>;

template class eh::estimation::SteadyStateKalman<eh::model::StateSpace<3, 1, 2>>;

template class eh::kinematics::CylindricalMapper<double>;
template class eh::kinematics::CylindricalMapper<float>;
template class eh::kinematics::DhChain<6>;
template class eh::kinematics::DhChain<3, float>;

template class eh::transport::DatagramQueue<128, 16>;
template class eh::transport::InMemoryTransport<128, 16>;
template class eh::transport::InMemoryLink<64, 4>;
template class eh::transport::FaultInjectingTransport<eh::transport::InMemoryTransport<128, 16>>;
template class eh::teleop::DurationStats<100, 1000>;
template class eh::teleop::SetpointRateLimiter<4>;
template class eh::sim::SimulatedRig<1, float>;
template class eh::sim::SimulatedRig<4>;
template class eh::sim::ScriptedOperator<eh::ManualClock>;
template class eh::sim::SbrioEmulator<eh::transport::InMemoryTransport<128, 16>,
                                      eh::sim::SimulatedRig<4>, eh::ManualClock>;
template class eh::estimation::PacedEstimator<eh::teleop::NoForceEstimator, eh::ManualClock>;
template class eh::teleop::TeleopLoop<eh::transport::InMemoryTransport<128, 16>,
                                      InstantiationDevice, eh::teleop::NoForceEstimator,
                                      eh::kinematics::CylindricalMapper<double>, eh::ManualClock>;
