//! @file
//! Error handling shared by every component: `endohaptics::Error`, the base of all
//! configuration-time exceptions (bad model, unreadable file, invalid option), and
//! `ENDOHAPTICS_ASSERT` for programmer errors. Real-time code never throws: it returns a status.
#pragma once

#include <stdexcept>
#include <string>

namespace endohaptics {

//! Thrown at configuration time only; the message says what was wrong and where.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace endohaptics

#ifndef ENDOHAPTICS_ASSERT
#include <cassert>
//! Programmer-error check (precondition violated by the caller's code, never by data).
//! Define ENDOHAPTICS_ASSERT before including any endohaptics header to override it.
#define ENDOHAPTICS_ASSERT(condition) assert(condition)
#endif
