// The receive spin of the UDP transports (UdpConfig::receive_spin, detail::ReadableWait): off by
// default, bounded, and a spinning receive returns the same datagrams at the same deadlines as a
// blocking one: a datagram that comes during the spin ends it, one that comes later is taken by
// the blocking wait after it, and no receive outlasts its timeout for a longer spin.
#include <doctest/doctest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <endohaptics/core/error.hpp>
#include <endohaptics/transport/udp_server_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <string>
#include <thread>

namespace transport_receive_spin_test {

namespace transport = endohaptics::transport;
using transport::TransportStatus;
using namespace std::chrono_literals;

namespace {

std::array<std::byte, 17> datagram(unsigned char first) {
  std::array<std::byte, 17> a{};
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i] = std::byte{static_cast<unsigned char>(first + i)};
  }
  return a;
}

// A server on 127.0.0.1 and a client connected to it, the client's receives spinning `spin`.
struct Pair {
  explicit Pair(std::chrono::nanoseconds spin)
      : server({.bind_address = "127.0.0.1", .port = 0}),
        client({.local_address = "127.0.0.1",
                .remote_address = "127.0.0.1",
                .remote_port = server.local_endpoint().port(),
                .receive_spin = spin}) {
    std::array<std::byte, 64> scratch{};
    REQUIRE(client.send(datagram(0)) == TransportStatus::ok);
    REQUIRE(server.receive(scratch, 1s).status == TransportStatus::ok);  // learns the peer
  }
  transport::UdpServerTransport server;
  transport::UdpTransport client;
};

std::string error_of(auto&& make) {
  try {
    make();
  } catch (const endohaptics::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("receive spin: off by default, so the bridge and the emulator block at once") {
  CHECK(transport::UdpConfig{}.receive_spin == 0ns);
  CHECK(transport::UdpServerConfig{}.receive_spin == 0ns);
  transport::UdpServerTransport server({.bind_address = "127.0.0.1", .port = 0});
  transport::UdpTransport client({.local_address = "127.0.0.1", .remote_address = "127.0.0.1"});
  CHECK(server.receive_wait().spin() == 0ns);
  CHECK(client.receive_wait().spin() == 0ns);
  std::array<std::byte, 64> buffer{};
  CHECK(client.receive(buffer, 1ms).status == TransportStatus::timeout);
  CHECK(client.receive_wait().spin_misses() == 0);  // no spin ran
}

TEST_CASE("receive spin: [0, 1 ms] accepted, anything else refused naming the field and value") {
  const auto client = [](std::chrono::nanoseconds spin) {
    return [spin] {
      transport::UdpTransport t(
          {.local_address = "127.0.0.1", .remote_address = "127.0.0.1", .receive_spin = spin});
      CHECK(t.receive_wait().spin() == spin);
    };
  };
  const auto server = [](std::chrono::nanoseconds spin) {
    return [spin] {
      transport::UdpServerTransport t(
          {.bind_address = "127.0.0.1", .port = 0, .receive_spin = spin});
      CHECK(t.receive_wait().spin() == spin);
    };
  };
  CHECK(error_of(client(0ns)).empty());
  CHECK(error_of(client(transport::max_receive_spin)).empty());
  CHECK(error_of(server(50us)).empty());
  const std::string too_long = error_of(client(transport::max_receive_spin + 1ns));
  CHECK(too_long.find("UdpTransport: receive_spin must be in [0, 1000000] ns") !=
        std::string::npos);
  CHECK(too_long.find("got 1000001 ns") != std::string::npos);
  const std::string negative = error_of(server(-1ns));
  CHECK(negative.find("UdpServerTransport: receive_spin") != std::string::npos);
  CHECK(negative.find("got -1 ns") != std::string::npos);
}

TEST_CASE("receive spin: a datagram that comes during the spin ends it, without a blocking wait") {
  Pair pair(1ms);
  std::array<std::byte, 64> buffer{};
  // Queued before the receive: found by the spin's first poll.
  REQUIRE(pair.server.send(datagram(1)) == TransportStatus::ok);
  auto r = pair.client.receive(buffer, 100ms);
  REQUIRE(r.status == TransportStatus::ok);
  CHECK(r.size == 17);
  CHECK(buffer[0] == std::byte{1});
  CHECK(pair.client.receive_wait().spin_hits() == 1);
  CHECK(pair.client.receive_wait().spin_misses() == 0);

  // Sent by another thread while the receive spins (the spin yields, so the sender gets the CPU
  // even on one core). A busy machine may delay the sender past the 1 ms spin now and then:
  // then the blocking wait takes it (a miss); every receive returns its datagram either way.
  int hits = 0;
  for (unsigned char i = 2; i < 22 && hits == 0; ++i) {
    const auto hits_before = pair.client.receive_wait().spin_hits();
    std::atomic<bool> go{false};
    std::thread sender([&] {
      while (!go.load()) std::this_thread::yield();
      // A moment after the receive began: into its spin, not before it.
      const auto at = std::chrono::steady_clock::now() + 100us;
      while (std::chrono::steady_clock::now() < at) std::this_thread::yield();
      (void)pair.server.send(datagram(i));
    });
    go.store(true);
    r = pair.client.receive(buffer, 1s);
    sender.join();
    REQUIRE(r.status == TransportStatus::ok);
    CHECK(buffer[0] == std::byte{i});
    hits += static_cast<int>(pair.client.receive_wait().spin_hits() - hits_before);
  }
  CHECK(hits == 1);
}

TEST_CASE("receive spin: a datagram later than the spin is taken by the blocking wait after it") {
  Pair pair(100us);
  std::array<std::byte, 64> buffer{};
  std::thread late([&] {
    std::this_thread::sleep_for(20ms);
    (void)pair.server.send(datagram(5));
  });
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = pair.client.receive(buffer, 2s);
  const auto elapsed = std::chrono::steady_clock::now() - t0;
  late.join();
  REQUIRE(r.status == TransportStatus::ok);
  CHECK(buffer[0] == std::byte{5});
  CHECK(elapsed >= 19ms);
  CHECK(elapsed < 1s);  // woken by the datagram, not by the 2 s timeout
  CHECK(pair.client.receive_wait().spin_hits() == 0);
  CHECK(pair.client.receive_wait().spin_misses() == 1);

  // The server's side spins the same way (the gateway's consoles' side).
  transport::UdpServerTransport server(
      {.bind_address = "127.0.0.1", .port = 0, .receive_spin = 100us});
  transport::UdpTransport client({.local_address = "127.0.0.1",
                                  .remote_address = "127.0.0.1",
                                  .remote_port = server.local_endpoint().port()});
  std::thread later([&] {
    std::this_thread::sleep_for(20ms);
    (void)client.send(datagram(6));
  });
  const auto s = server.receive(buffer, 2s);
  later.join();
  REQUIRE(s.status == TransportStatus::ok);
  CHECK(buffer[0] == std::byte{6});
  CHECK(server.receive_wait().spin_misses() == 1);
}

TEST_CASE("receive spin: a receive never outlasts its timeout for a longer spin") {
  Pair pair(transport::max_receive_spin);
  std::array<std::byte, 64> buffer{};
  // A zero timeout looks once and does not spin.
  CHECK(pair.client.receive(buffer, 0ns).status == TransportStatus::timeout);
  CHECK(pair.client.receive_wait().spin_misses() == 0);
  REQUIRE(pair.server.send(datagram(3)) == TransportStatus::ok);
  std::this_thread::sleep_for(5ms);
  CHECK(pair.client.receive(buffer, 0ns).status == TransportStatus::ok);  // ... and finds this

  // 100 receives of 50 us with a 1 ms spin: a spin that ignored the deadline would take 100 ms
  // at least; one that ends at it takes about 5 ms (80 ms leaves room for a busy machine).
  constexpr int n = 100;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    const auto t = std::chrono::steady_clock::now();
    REQUIRE(pair.client.receive(buffer, 50us).status == TransportStatus::timeout);
    CHECK(std::chrono::steady_clock::now() - t >= 50us);  // nor ends before it
  }
  CHECK(std::chrono::steady_clock::now() - t0 < 80ms);
  CHECK(pair.client.receive_wait().spin_misses() == static_cast<std::uint64_t>(n));
}

}  // namespace transport_receive_spin_test
