// TeleopLoop tick cost over an in-memory transport, and a UDP loopback round trip through
// UdpTransport side by side with a raw POSIX socket ping-pong against the same echo thread.
#include <arpa/inet.h>
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <endohaptics/kinematics/cylindrical_mapper.hpp>
#include <endohaptics/teleop/teleop_loop.hpp>
#include <endohaptics/transport/in_memory_transport.hpp>
#include <endohaptics/transport/udp_transport.hpp>
#include <thread>

namespace teleop_loop_bench {

namespace {

namespace transport = endohaptics::transport;
namespace tp = endohaptics::teleop;
using Codec = endohaptics::protocol::PacketCodec<4>;

// Replies to every setpoint with a fixed, pre-encoded state: the tick's own cost dominates.
struct CannedSbrio {
  Codec::StateBytes reply{};
  CannedSbrio() {
    Codec::State s;
    s.position << 0.1, -0.2, 0.3, -0.3;
    s.current << 0.4, 0.5, 0.6, -0.6;
    s.active_mask = 0x0F;
    (void)Codec::encode_state(s, reply);
  }
  template <typename Reply>
  void operator()(std::span<const std::byte>, Reply& out) noexcept {
    (void)out.send(reply);
  }
};

struct StillDevice {
  int t = 0;
  tp::DeviceStatus read(tp::StylusSample& s) noexcept {
    s.position = Eigen::Vector3d(0.1 + 1e-6 * (t++ % 100), 0.12, 0.02);
    return tp::DeviceStatus::ok;
  }
  tp::DeviceStatus command_force(const Eigen::Vector3d& f) noexcept {
    benchmark::DoNotOptimize(f);
    return tp::DeviceStatus::ok;
  }
};

struct EffortEstimator {
  bool estimate(const tp::MotorState4& m, const tp::MotorVector&, tp::MotorVector& f) noexcept {
    f = 0.5 * m.current;
    return true;
  }
  void reset() noexcept {}
};

void BM_TeleopLoop_tick(benchmark::State& st) {
  transport::RespondingTransport<CannedSbrio> transport{CannedSbrio{}};
  StillDevice device;
  EffortEstimator estimator;
  endohaptics::kinematics::CylindricalMapper<> mapper;
  endohaptics::SteadyClock clock;
  tp::TeleopLoop loop(transport, device, estimator, mapper, clock);
  for (auto _ : st) {
    const auto r = loop.tick();
    benchmark::DoNotOptimize(r.stylus_force);
  }
}
BENCHMARK(BM_TeleopLoop_tick);

// Echo thread on 127.0.0.1 answering every datagram to its sender; a 1-byte datagram stops it.
class Echo {
 public:
  Echo() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] {
      std::array<char, 256> buf{};
      for (;;) {
        sockaddr_in from{};
        socklen_t fl = sizeof from;
        const ssize_t n =
            ::recvfrom(fd_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&from), &fl);
        if (n <= 1) break;
        ::sendto(fd_, buf.data(), static_cast<std::size_t>(n), 0,
                 reinterpret_cast<sockaddr*>(&from), fl);
      }
    });
  }
  ~Echo() {
    const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port_);
    const char stop = 0;
    ::sendto(s, &stop, 1, 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
    thread_.join();
    ::close(s);
    ::close(fd_);
  }
  std::uint16_t port() const { return port_; }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
  std::thread thread_;
};

void BM_UdpTransport_round_trip(benchmark::State& st) {
  Echo echo;
  transport::UdpTransport transport(
      {.local_address = "127.0.0.1", .remote_address = "127.0.0.1", .remote_port = echo.port()});
  Codec::SetpointBytes out{};
  std::array<std::byte, 128> in{};
  std::int64_t lost = 0;
  for (auto _ : st) {
    (void)transport.send(out);
    const auto r = transport.receive(in, std::chrono::milliseconds(100));
    if (r.status != transport::TransportStatus::ok) ++lost;
  }
  st.counters["lost"] = static_cast<double>(lost);
}
BENCHMARK(BM_UdpTransport_round_trip)->UseRealTime();

void BM_BaselinePosix_udp_round_trip(benchmark::State& st) {
  Echo echo;
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(echo.port());
  ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  std::array<char, 17> out{};
  std::array<char, 128> in{};
  for (auto _ : st) {
    ::send(fd, out.data(), out.size(), 0);
    const ssize_t n = ::recv(fd, in.data(), in.size(), 0);  // blocking: the cheapest possible wait
    benchmark::DoNotOptimize(n);
  }
  ::close(fd);
}
BENCHMARK(BM_BaselinePosix_udp_round_trip)->UseRealTime();

}  // namespace

}  // namespace teleop_loop_bench
