// Instantiates every member of every class template, so an unused member cannot hide an error.
// One argument list per template (plus float where the template takes a scalar): every distinct
// size instantiates Eigen's decompositions again, and this file used to cost over 3 minutes of
// compile time. The tests cover the other sizes.
#include <endohaptics/endohaptics.hpp>
#include <endohaptics/estimation/force_estimator.hpp>

#include <type_traits>

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
template class eh::model::StateSpace<Eigen::Dynamic, Eigen::Dynamic, Eigen::Dynamic>;
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
template class eh::estimation::StallHold<double>;
template class eh::estimation::StallHold<float>;
template class eh::estimation::PushLoadObserver<double>;
template class eh::estimation::PushLoadObserver<float>;
template class eh::estimation::BidirectionalLoadObserver<double>;
template class eh::estimation::BidirectionalLoadObserver<float>;
template struct eh::estimation::BidirectionalLoadObserverParameters<double>;
template class eh::model::StopOperators<double, 8>;
template class eh::model::StopOperators<float, 3>;
template struct eh::model::ButterworthBiquad<double>;
template struct eh::model::ButterworthBiquad<float>;
template class eh::estimation::CurrentOffsetReference<double>;
template class eh::estimation::CurrentOffsetReference<float>;

// ForceEstimator. The rate policies (rate::SameRate, Decimate, Resample) are not templates:
// their code is the stepper ForceEstimator instantiates, so ForceEstimator gets one argument
// list per policy, all on the 2016 models (those of its requires-constrained default
// constructor, which clang 14 instantiates) and so no Eigen size beyond the first.
// ForceEstimator2016 is an alias template (not instantiable): checked to name them. OpenLoop on
// the three 2016 joint models (ForceEstimator uses them; here every member), KalmanCorrected on
// the StateSpace<3, 1, 2> above. Each also in float. All of it adds ~2 s of clang 14 time.
namespace est = eh::estimation;
template struct est::JointState<double>;
template struct est::JointState<float>;
template struct est::JointSignals<double>;
template struct est::JointSignals<float>;
template struct est::ForceEstimatorSettings<double>;
template struct est::ForceEstimatorSettings<float>;
template class est::OpenLoop<eh::model::StateSpace<1, 1, 1>>;
template class est::OpenLoop<eh::model::StateSpace<6, 2, 1>>;
template class est::OpenLoop<eh::model::YawForceHW2016<double>>;
template class est::OpenLoop<eh::model::StateSpace<1, 1, 1, float>>;
template class est::OpenLoop<eh::model::StateSpace<6, 2, 1, float>>;
template class est::OpenLoop<eh::model::YawForceHW2016<float>>;
template class est::KalmanCorrected<3, 1, 2>;
template class est::KalmanCorrected<3, 1, 2, float>;
template struct est::ForceModels<est::RollModel2016<>, est::PitchModel2016<>,
                                 est::ClampModel2016<>>;
template struct est::ForceModels<est::RollModel2016<float>, est::PitchModel2016<float>,
                                 est::ClampModel2016<float>>;
template class est::ForceEstimator<est::rate::Decimate, est::RollModel2016<>, est::PitchModel2016<>,
                                   est::ClampModel2016<>>;
template class est::ForceEstimator<est::rate::SameRate, est::RollModel2016<>, est::PitchModel2016<>,
                                   est::ClampModel2016<>>;
template class est::ForceEstimator<est::rate::Resample, est::RollModel2016<>, est::PitchModel2016<>,
                                   est::ClampModel2016<>>;
template class est::ForceEstimator<est::rate::Decimate, est::RollModel2016<float>,
                                   est::PitchModel2016<float>, est::ClampModel2016<float>>;
static_assert(std::is_same_v<est::ForceEstimator2016<>,
                             est::ForceEstimator<est::rate::Decimate, est::RollModel2016<>,
                                                 est::PitchModel2016<>, est::ClampModel2016<>>>);
static_assert(std::is_same_v<est::ForceEstimator2016<est::rate::SameRate>,
                             est::ForceEstimator<est::rate::SameRate, est::RollModel2016<>,
                                                 est::PitchModel2016<>, est::ClampModel2016<>>>);
static_assert(std::is_same_v<est::ForceEstimator2016<est::rate::Resample>,
                             est::ForceEstimator<est::rate::Resample, est::RollModel2016<>,
                                                 est::PitchModel2016<>, est::ClampModel2016<>>>);
static_assert(
    std::is_same_v<est::ForceEstimator2016<est::rate::Decimate, float>,
                   est::ForceEstimator<est::rate::Decimate, est::RollModel2016<float>,
                                       est::PitchModel2016<float>, est::ClampModel2016<float>>>);

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
template class eh::teleop::LatestValue<eh::teleop::StylusSample>;
template class eh::sim::SimulatedRig<1, float>;
template class eh::sim::SimulatedRig<4>;
template class eh::sim::ScriptedOperator<eh::ManualClock>;
template class eh::sim::HapticDeviceModel<eh::ManualClock>;
template class eh::sim::DelayLine<>;
template class eh::sim::DelayedSendTransport<eh::transport::InMemoryTransport<128, 16>,
                                             eh::ManualClock>;
template class eh::sim::SbrioEmulator<eh::transport::InMemoryTransport<128, 16>,
                                      eh::sim::SimulatedRig<4>, eh::ManualClock>;
template class eh::estimation::PacedEstimator<eh::teleop::NoForceEstimator, eh::ManualClock>;
template class eh::teleop::TeleopLoop<eh::transport::InMemoryTransport<128, 16>,
                                      InstantiationDevice, eh::teleop::NoForceEstimator,
                                      eh::kinematics::CylindricalMapper<double>, eh::ManualClock>;
