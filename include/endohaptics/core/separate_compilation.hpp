//! @file
//! ENDOHAPTICS_DECL: how the offline layers (files/, identification/, workflow/) declare their
//! non-template functions. By default the library is header-only: the macro is `inline` and every
//! offline header includes its function bodies (`<area>/impl/<header>.ipp`) at its end. With
//! ENDOHAPTICS_SEPARATE_COMPILATION defined, the headers only declare those functions and one
//! translation unit per area compiles the bodies for the whole program (Asio's model), so the
//! identification, workflow and file code is compiled once per build instead of once per
//! program or test that includes it: this project's own tests, programs and benchmarks build that
//! way (CMakeLists.txt, `endohaptics_add_offline_library`; docs/development.md). The real-time
//! core has no such functions: its headers are templates or small inline functions.
//!
//! ENDOHAPTICS_EXTERN_NUMERICS, separately: the core's heavy configuration-time templates
//! (model/dense_numerics.hpp, estimation/dare.hpp) are declared `extern template` for double,
//! and `model/impl/dense_numerics.ipp` and `estimation/impl/dare.ipp`, compiled once each,
//! instantiate them (explicit instantiations only: no header includes them). This project's unit
//! tests and sanitized benchmarks build that way (many translation units use them); its programs do
//! not (only the bridge does: compiling them apart cost more than it saved,
//! docs/history/build-times.md, step 13).
#pragma once

#if defined(ENDOHAPTICS_SEPARATE_COMPILATION)
//! Linkage of the offline layers' non-template functions: external, compiled once.
#define ENDOHAPTICS_DECL
#else
//! Linkage of the offline layers' non-template functions: `inline` (header-only, the default).
#define ENDOHAPTICS_DECL inline
#endif
