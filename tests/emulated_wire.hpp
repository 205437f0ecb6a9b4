// A PC-side transport for unit tests that run the teleoperation loop against the sbRIO emulator
// in simulated time: a datagram sent reaches the emulator, which answers after `latency` of the
// clock's time (inside send); a receive that times out has waited its timeout.
#pragma once

#include <chrono>
#include <cstddef>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <span>

namespace test_support {

//! `Emulator`: sim::SbrioEmulator over the link's other end; `Clock`: a clock with advance().
//! Aggregate: {&link.a(), &emulator, &clock} (latency 100 us) or with a latency last.
template <typename Emulator, typename Clock>
struct EmulatedWire {
  endohaptics::transport::InMemoryTransport<>* pc;
  Emulator* emulator;
  Clock* clock;
  std::chrono::nanoseconds latency = std::chrono::microseconds(100);

  endohaptics::transport::TransportStatus send(std::span<const std::byte> datagram) noexcept {
    const auto status = pc->send(datagram);
    clock->advance(latency);
    (void)emulator->poll(std::chrono::nanoseconds(0));
    return status;
  }
  endohaptics::transport::ReceiveResult receive(std::span<std::byte> buffer,
                                                std::chrono::nanoseconds timeout) noexcept {
    const auto r = pc->receive(buffer, timeout);
    if (r.status == endohaptics::transport::TransportStatus::timeout) clock->advance(timeout);
    return r;
  }
};

}  // namespace test_support
