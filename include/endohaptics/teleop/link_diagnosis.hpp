//! @file
//! Why a link never came up: the likeliest cause of a run (or its first second) without a valid,
//! obeyed state, from the loop's counters and the datagrams the protocol layer refused. For the
//! programs' warnings and exit status; allocates the message, so never called in a tick.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "endohaptics/teleop/loop_stats.hpp"

namespace endohaptics::teleop {

//! The likeliest reason no obeyed state arrived, most specific first.
enum class LinkProblem : std::uint8_t {
  none,            //!< the robot obeyed: the link was up
  no_answer,       //!< nothing came back at all
  wrong_key,       //!< v2: answers arrived but none authenticated (different keys)
  wrong_protocol,  //!< datagrams of the other protocol's size (2016 vs v2)
  late_answers,    //!< v2: authentic answers, all to older setpoints than the lag allows
  wrong_session,   //!< v2: authentic answers of another session (a restart, another console)
  garbled,         //!< datagrams arrived but none decoded (NaN/Inf, mask bits, size)
  implausible,     //!< states decoded but were implausible (StateFault)
  not_obeyed,      //!< states arrived, but the motors enabled stayed inactive
};

//! The problem's name for logs ("no answer", "wrong key", ...).
[[nodiscard]] constexpr std::string_view to_string(LinkProblem p) noexcept {
  switch (p) {
    case LinkProblem::none:
      return "none";
    case LinkProblem::no_answer:
      return "no answer";
    case LinkProblem::wrong_key:
      return "wrong key";
    case LinkProblem::wrong_protocol:
      return "wrong protocol";
    case LinkProblem::late_answers:
      return "late answers";
    case LinkProblem::wrong_session:
      return "wrong session";
    case LinkProblem::garbled:
      return "garbled";
    case LinkProblem::implausible:
      return "implausible states";
    case LinkProblem::not_obeyed:
      return "not obeyed";
  }
  return "unknown";
}

//! What the protocol layer under the loop refused (zero for the 2016 wire, which has none).
struct LinkEvidence {
  bool authenticated = false;       //!< protocol v2 (else the 2016 wire)
  std::uint64_t forged = 0;         //!< v2: tags that did not verify
  std::uint64_t wrong_size = 0;     //!< v2: datagrams of another length
  std::uint64_t wrong_session = 0;  //!< v2: authentic, another session
  std::uint64_t late = 0;           //!< v2: authentic, answering a setpoint older than the lag
  std::uint64_t sessions = 0;       //!< v2: handshakes completed (the robot side answered one)
  std::uint8_t enable_mask = 0;     //!< the motors the loop enabled
  std::uint8_t last_active = 0;     //!< the active mask of the newest state received
};

//! The verdict on a run so far.
struct LinkDiagnosis {
  LinkProblem problem = LinkProblem::none;  //!< none: an obeyed state arrived
  std::string message;                      //!< one sentence with the likely fix

  //! True when the robot obeyed at least once.
  [[nodiscard]] bool up() const noexcept { return problem == LinkProblem::none; }
};

//! The verdict from the loop's counters (`stats`: the run so far, or one window) and what the
//! protocol layer refused. `peer`: "HOST:PORT" of the robot side, for the message.
[[nodiscard]] inline LinkDiagnosis diagnose_link(const LoopWindow& stats,
                                                 const LinkEvidence& evidence,
                                                 std::string_view peer) {
  const auto n = [](std::uint64_t v) { return std::to_string(v); };
  const auto hex = [](unsigned v) {
    char text[8];
    std::snprintf(text, sizeof text, "0x%02X", v & 0xFFu);
    return std::string(text);
  };
  const std::string at = std::string(peer);
  LinkDiagnosis d;
  if (stats.received > 0) return d;
  if (stats.not_obeyed > 0) {
    d.problem = LinkProblem::not_obeyed;
    d.message = "the robot at " + at + " answers (" + n(stats.not_obeyed) +
                " states) but does not obey: motors " + hex(evidence.enable_mask) +
                " enabled, reported active " + hex(evidence.last_active) +
                " (the robot side does not enable them: a fault or a safety stop on its side)";
    return d;
  }
  if (evidence.authenticated && evidence.forged > 0 && evidence.wrong_session == 0 &&
      evidence.late == 0) {
    d.problem = LinkProblem::wrong_key;
    d.message = n(evidence.forged) + " answers from " + at +
                " failed authentication: the two sides hold different keys (--key)";
    return d;
  }
  const std::uint64_t wrong_size = evidence.wrong_size + stats.rejected;
  if (wrong_size > 0 && stats.decode_errors == 0 && stats.state_faults == 0 &&
      evidence.wrong_session == 0 && evidence.late == 0) {
    d.problem = LinkProblem::wrong_protocol;
    d.message = n(wrong_size) + " datagrams from " + at + " had the other protocol's size: " +
                (evidence.authenticated
                     ? "the robot side speaks the 2016 wire (give both --protocol 2016, or "
                       "run the robot side with protocol v2)"
                     : "the robot side speaks protocol v2 (give both the same --protocol)");
    return d;
  }
  if (evidence.late > 0) {
    d.problem = LinkProblem::late_answers;
    d.message = n(evidence.late) + " authentic answers from " + at +
                " answered older setpoints than --max-answer-lag allows: the round trip is "
                "longer; raise --max-answer-lag (setpoints) above it";
    return d;
  }
  if (evidence.wrong_session > 0) {
    d.problem = LinkProblem::wrong_session;
    d.message = n(evidence.wrong_session) + " authentic answers from " + at +
                " belonged to another session (a restarted robot side, or another console's)";
    return d;
  }
  if (stats.state_faults > 0) {
    d.problem = LinkProblem::implausible;
    d.message = n(stats.state_faults) + " states from " + at +
                " were implausible (positions, velocities or currents out of range)";
    return d;
  }
  if (stats.decode_errors > 0 || wrong_size > 0) {
    d.problem = LinkProblem::garbled;
    d.message = n(stats.decode_errors) + " datagrams from " + at +
                " did not decode (wrong size, NaN/Inf or mask bits)";
    return d;
  }
  if (evidence.authenticated && evidence.sessions > 0) {
    d.problem = LinkProblem::late_answers;
    d.message = "the robot side at " + at + " answered the handshake (" + n(evidence.sessions) +
                " sessions) but no state came back: its setpoints arrived later than the round "
                "trip it grants (raise the robot side's --max-round-trip), or the states are lost";
    return d;
  }
  d.problem = LinkProblem::no_answer;
  d.message =
      "no answer from " + at +
      (evidence.authenticated
           ? ": the robot side (sbRIO gateway or emulator) is not running there, holds another "
             "key, has another --rig name, speaks the 2016 wire, or the round trip is longer "
             "than the run so far (a v2 robot side answers nothing but a handshake under its "
             "key for its rig)"
           : ": the robot side is not running there, speaks protocol v2, obeys another console "
             "(a 2016 robot side pins one console), or the round trip is longer than the run so "
             "far");
  return d;
}

}  // namespace endohaptics::teleop
