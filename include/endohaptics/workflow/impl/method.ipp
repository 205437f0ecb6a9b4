//! @file
//! Function bodies of workflow/method.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/workflow/method.hpp"

namespace endohaptics::workflow {

ENDOHAPTICS_DECL std::vector<Method> parse_methods(std::string_view list) {
  std::vector<Method> methods;
  std::string_view rest = list;
  for (;;) {
    const std::size_t comma = rest.find(',');
    const std::string_view name = rest.substr(0, comma);
    bool known = false;
    if (name == "best") {
      methods.insert(methods.end(), {Method::n4sid, Method::moesp, Method::cva});
      known = true;
    }
    for (const MethodName& m : method_names) {
      if (!known && name == m.name) {
        methods.push_back(m.method);
        known = true;
      }
    }
    if (!known) {
      std::string names;
      for (const MethodName& m : method_names) names += std::string(m.name) + ", ";
      ENDOHAPTICS_THROW(Error("--method " + std::string(list) + ": unknown method \"" +
                              std::string(name) + "\" (expected a comma list of " + names +
                              "best)"));
    }
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return methods;
}

}  // namespace endohaptics::workflow
