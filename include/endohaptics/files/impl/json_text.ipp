//! @file
//! Function bodies of files/json_text.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include "endohaptics/files/json_text.hpp"

namespace endohaptics::files::detail::json_text {

ENDOHAPTICS_DECL std::string excerpt(std::string_view text, std::size_t max) {
  std::string out(text.substr(0, max));
  for (char& c : out) {  // control characters and bytes of (possibly invalid) UTF-8
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  return text.size() > max ? out + "..." : out;
}

ENDOHAPTICS_DECL std::string show(const json& value) {
  if (value.is_number_float() && !std::isfinite(value.get<double>())) {
    return "a number beyond the double range";
  }
  return excerpt(value.dump(-1, ' ', /*ensure_ascii=*/true));
}

ENDOHAPTICS_DECL std::string key_name(std::string_view key) {
  const std::string escaped = json(std::string(key)).dump(-1, ' ', /*ensure_ascii=*/true);
  return "'" + excerpt(std::string_view(escaped).substr(1, escaped.size() - 2)) + "'";
}

ENDOHAPTICS_DECL void check_depth(std::string_view text, std::string_view source, int max_depth,
                                  std::string_view needed) {
  int depth = 0;
  std::size_t line = 1;
  std::size_t column = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    ++column;
    if (ch == '\n') {
      ++line;
      column = 0;
    } else if (ch == '"') {  // a string: skip to its closing quote
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') ++i;
        if (i < text.size() && text[i] == '\n') {  // invalid JSON; keep the position right
          ++line;
          column = 0;
        }
        ++column;
      }
      ++column;
    } else if (ch == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      while (i < text.size() && text[i] != '\n') ++i;
      ++line;
      column = 0;
    } else if (ch == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      for (i += 2; i + 1 < text.size() && !(text[i] == '*' && text[i + 1] == '/'); ++i) {
        if (text[i] == '\n') {
          ++line;
          column = 0;
        }
      }
      ++i;
    } else if (ch == '[' || ch == '{') {
      if (++depth > max_depth) {
        ENDOHAPTICS_THROW(Error(std::string(source) + ": line " + std::to_string(line) +
                                ", column " + std::to_string(column) + ": nested deeper than " +
                                std::to_string(max_depth) + " levels (the limit; " +
                                std::string(needed) + ")"));
      }
    } else if (ch == ']' || ch == '}') {
      --depth;
    }
  }
}

ENDOHAPTICS_DECL std::string parse_message(const json::exception& e) {
  std::string m = e.what();
  if (const auto p = m.find("] "); m.rfind("[json.exception", 0) == 0 && p != std::string::npos) {
    m.erase(0, p + 2);
  }
  // The echoed token: after "last read: '" (parse errors) or the first "'" (other errors), up to
  // "'; expected " or the final "'".
  constexpr std::string_view marker = "; last read: '";
  std::size_t start = std::string::npos;
  if (const auto p = m.find(marker); p != std::string::npos) {
    start = p + marker.size();
  } else if (const auto q = m.find('\''); q != std::string::npos) {
    start = q + 1;
  }
  if (start != std::string::npos) {
    std::size_t end = m.find("'; expected ", start);
    if (end == std::string::npos) {
      end = m.size() > start && m.back() == '\'' ? m.size() - 1 : m.size();
    }
    m = m.substr(0, start) + excerpt(std::string_view(m).substr(start, end - start)) +
        m.substr(end);
  }
  return excerpt(m, 300);
}

ENDOHAPTICS_DECL json parse_strict(std::string_view text, std::string_view source,
                                   const Limits& limits) {
  check_depth(text, source, limits.max_depth, limits.needed);
  struct Frame {
    bool object = false;
    std::string path;         // "" for the root, "safety", "a.b", "list[]"
    std::string current_key;  // the object's newest key
    std::set<std::string> keys;
  };
  std::vector<Frame> frames;
  std::string duplicate;
  const json::parser_callback_t callback = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start: {
        Frame f;
        f.object = event == json::parse_event_t::object_start;
        if (!frames.empty()) {
          const Frame& parent = frames.back();
          f.path = parent.object
                       ? (parent.path.empty() ? "" : parent.path + ".") + parent.current_key
                       : parent.path + "[]";
        }
        frames.push_back(std::move(f));
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!frames.empty()) frames.pop_back();
        break;
      case json::parse_event_t::key:
        if (!frames.empty()) {
          Frame& f = frames.back();
          f.current_key = parsed.get<std::string>();
          if (!f.keys.insert(f.current_key).second && duplicate.empty()) {
            duplicate = (f.path.empty() ? "" : f.path + ".") + f.current_key;
          }
        }
        break;
      case json::parse_event_t::value:
        break;
    }
    return true;
  };
  json j;
#if defined(__cpp_exceptions)
  try {
    j = json::parse(text.begin(), text.end(), callback, /*allow_exceptions=*/true, limits.comments);
  } catch (const json::exception& e) {  // parse_error; out_of_range for a number overflow
    ENDOHAPTICS_THROW(Error(std::string(source) + ": not valid JSON: " + parse_message(e)));
  }
#else
  j = json::parse(text.begin(), text.end(), callback, /*allow_exceptions=*/false, limits.comments);
  if (j.is_discarded()) ENDOHAPTICS_THROW(Error(std::string(source) + ": not valid JSON"));
#endif
  if (!duplicate.empty()) {
    ENDOHAPTICS_THROW(Error(std::string(source) + ": duplicate key " + key_name(duplicate) +
                            " (a key may appear only once)"));
  }
  return j;
}

ENDOHAPTICS_DECL std::string read_bounded(const std::filesystem::path& path, std::size_t max_bytes,
                                          std::string_view what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    ENDOHAPTICS_THROW(Error(std::string(what) + " " + path.string() + ": cannot be opened"));
  }
  std::string text(max_bytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) {
    ENDOHAPTICS_THROW(Error(std::string(what) + " " + path.string() + ": cannot be read"));
  }
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > max_bytes) {
    ENDOHAPTICS_THROW(Error(std::string(what) + " " + path.string() + ": larger than " +
                            std::to_string(max_bytes) + " bytes (the limit)"));
  }
  return text;
}

}  // namespace endohaptics::files::detail::json_text
