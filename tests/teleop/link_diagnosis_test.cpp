#include <doctest/doctest.h>

#include <endohaptics/teleop/link_diagnosis.hpp>

namespace teleop_link_diagnosis_test {

namespace {

namespace tp = endohaptics::teleop;

tp::LoopWindow window(std::uint64_t received, std::uint64_t timeouts) {
  tp::LoopWindow w;
  w.received = received;
  w.timeouts = timeouts;
  w.exchanges = received + timeouts;
  return w;
}

}  // namespace

TEST_CASE("diagnose_link: up only when an obeyed state arrived, otherwise the likeliest cause") {
  const std::string peer = "127.0.0.1:61556";
  CHECK(tp::diagnose_link(window(10, 0), {}, peer).up());

  auto silent = tp::diagnose_link(window(0, 900), {}, peer);
  CHECK(silent.problem == tp::LinkProblem::no_answer);
  CHECK(silent.message.find("no answer from 127.0.0.1:61556") != std::string::npos);

  tp::LoopWindow refused = window(0, 900);
  refused.not_obeyed = 850;
  auto disobeyed = tp::diagnose_link(
      refused, {.authenticated = true, .enable_mask = 0x0F, .last_active = 0x00}, peer);
  CHECK(disobeyed.problem == tp::LinkProblem::not_obeyed);
  CHECK(disobeyed.message.find("motors 0x0F enabled, reported active 0x00") != std::string::npos);
  // A v2 robot side obeys every setpoint of its session: a motor that stays inactive is its own
  // doing (every setpoint it answered was fresh), the same words as for the 2016 wire.
  CHECK(disobeyed.message.find("a fault or a safety stop") != std::string::npos);
  auto pinned = tp::diagnose_link(refused, {.enable_mask = 0x0F}, peer);
  CHECK(pinned.message.find("a fault or a safety stop") != std::string::npos);
  CHECK(tp::diagnose_link(window(0, 900), {}, peer).message.find("pins one console") !=
        std::string::npos);

  CHECK(tp::diagnose_link(window(0, 900), {.authenticated = true, .forged = 900}, peer).problem ==
        tp::LinkProblem::wrong_key);
  CHECK(
      tp::diagnose_link(window(0, 900), {.authenticated = true, .wrong_size = 900}, peer).problem ==
      tp::LinkProblem::wrong_protocol);
  tp::LoopWindow sized = window(0, 900);
  sized.rejected = 900;  // the 2016 loop saw 99-byte datagrams
  CHECK(tp::diagnose_link(sized, {}, peer).problem == tp::LinkProblem::wrong_protocol);
  CHECK(tp::diagnose_link(window(0, 900), {.authenticated = true, .late = 400}, peer).problem ==
        tp::LinkProblem::late_answers);
  CHECK(tp::diagnose_link(window(0, 900), {.authenticated = true, .wrong_session = 4}, peer)
            .problem == tp::LinkProblem::wrong_session);
  // The robot side shook hands but no state came back: its grant is shorter than the round trip.
  const auto shook =
      tp::diagnose_link(window(0, 900), {.authenticated = true, .sessions = 3}, peer);
  CHECK(shook.problem == tp::LinkProblem::late_answers);
  CHECK(shook.message.find("answered the handshake (3 sessions)") != std::string::npos);
  CHECK(shook.message.find("--max-round-trip") != std::string::npos);
  CHECK(tp::diagnose_link(window(0, 900), {.authenticated = true}, peer)
            .message.find("another --rig name") != std::string::npos);
  tp::LoopWindow faults = window(0, 900);
  faults.state_faults = 3;
  CHECK(tp::diagnose_link(faults, {}, peer).problem == tp::LinkProblem::implausible);
  for (int p = 0; p <= static_cast<int>(tp::LinkProblem::not_obeyed); ++p) {
    CHECK(tp::to_string(static_cast<tp::LinkProblem>(p)) != "unknown");
  }
}

}  // namespace teleop_link_diagnosis_test
