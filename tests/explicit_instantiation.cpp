// Instantiates every member of every class template, so an unused member cannot hide an error.
#include <endohaptics/endohaptics.hpp>

template class endohaptics::protocol::PacketCodec<1>;
template class endohaptics::protocol::PacketCodec<4>;
template class endohaptics::protocol::PacketCodec<8>;
template struct endohaptics::protocol::MotorState<4>;
template struct endohaptics::protocol::MotorSetpoint<4>;
