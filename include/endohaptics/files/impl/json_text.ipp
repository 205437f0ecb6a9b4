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

namespace strict {

//! A pointer into the text that the parser advances; every copy reports the furthest position
//! read to `furthest`, so that the handler knows where the parser stands (nlohmann's SAX events
//! carry no position).
class TrackingIterator {
 public:
  using iterator_category = std::forward_iterator_tag;  //!< as a const char*
  using value_type = char;                              //!< bytes
  using difference_type = std::ptrdiff_t;               //!< as a const char*
  using pointer = const char*;                          //!< as a const char*
  using reference = const char&;                        //!< as a const char*

  TrackingIterator() = default;
  //! At `p`; advancing records the furthest position in `*furthest`.
  TrackingIterator(const char* p, const char** furthest) : p_(p), furthest_(furthest) {}
  reference operator*() const { return *p_; }
  TrackingIterator& operator++() {
    ++p_;
    if (furthest_ != nullptr && p_ > *furthest_) *furthest_ = p_;
    return *this;
  }
  TrackingIterator operator++(int) {
    TrackingIterator old = *this;
    ++*this;
    return old;
  }
  bool operator==(const TrackingIterator& other) const { return p_ == other.p_; }

 private:
  const char* p_ = nullptr;
  const char** furthest_ = nullptr;
};

//! nlohmann's SAX events -> a json value, as its json_sax_dom_parser builds it, with the depth
//! limit and duplicate keys checked as the events come: returning false stops the parser at once.
class Handler {
 public:
  using number_integer_t = json::number_integer_t;    //!< nlohmann's
  using number_unsigned_t = json::number_unsigned_t;  //!< nlohmann's
  using number_float_t = json::number_float_t;        //!< nlohmann's
  using string_t = json::string_t;                    //!< nlohmann's
  using binary_t = json::binary_t;                    //!< nlohmann's

  Handler(std::string_view text, const char* const* furthest, const Limits& limits)
      : text_(text), furthest_(furthest), limits_(limits) {}

  bool null() { return value(nullptr); }
  bool boolean(bool v) { return value(v); }
  bool number_integer(number_integer_t v) { return value(v); }
  bool number_unsigned(number_unsigned_t v) { return value(v); }
  bool number_float(number_float_t v, const string_t& /*text*/) { return value(v); }
  bool string(string_t& v) { return value(std::move(v)); }
  bool binary(binary_t& v) { return value(std::move(v)); }
  bool start_object(std::size_t /*elements*/) { return start(json::value_t::object); }
  bool start_array(std::size_t /*elements*/) { return start(json::value_t::array); }
  bool end_object() { return end(); }
  bool end_array() { return end(); }
  bool key(string_t& k) {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second) {
      error_ = position() + "duplicate key " + key_name((f.path.empty() ? "" : f.path + ".") + k) +
               " (a key may appear only once)";
      return false;
    }
    f.key = std::move(k);
    return true;
  }
  bool parse_error(std::size_t /*position*/, const std::string& /*last_token*/,
                   const json::exception& e) {
    error_ = "not valid JSON: " + parse_message(e);
    return false;
  }

  //! The value parsed (when sax_parse returned true).
  [[nodiscard]] json& root() { return root_; }
  //! Why parsing stopped ("" if it did not).
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  struct Frame {
    json* container = nullptr;
    std::string path;  // "" for the root, "safety", "a.b", "list[]"
    std::string key;   // an object's newest key
    std::set<std::string> keys;
  };

  // "line L, column C: " of the last byte the parser read (a bracket or a key's closing quote:
  // the lexer reads no further before reporting them); lines counted at '\n', as nlohmann does.
  [[nodiscard]] std::string position() const {
    const std::size_t at = static_cast<std::size_t>(*furthest_ - text_.data()) - 1;
    const std::string_view before = text_.substr(0, at);
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
    const std::size_t newline = before.rfind('\n');
    const std::size_t column = newline == std::string_view::npos ? at + 1 : at - newline;
    return "line " + std::to_string(line) + ", column " + std::to_string(column) + ": ";
  }

  // Places `v` where the parser stands: the root, the end of an array, or the value of the
  // object's newest key; returns where it went.
  template <typename Value>
  json* place(Value&& v) {
    if (frames_.empty()) {
      root_ = json(std::forward<Value>(v));
      return &root_;
    }
    Frame& f = frames_.back();
    if (f.container->is_array()) {
      f.container->emplace_back(std::forward<Value>(v));
      return &f.container->back();
    }
    json& slot = (*f.container)[f.key];
    slot = json(std::forward<Value>(v));
    return &slot;
  }
  template <typename Value>
  bool value(Value&& v) {
    (void)place(std::forward<Value>(v));
    return true;
  }
  bool start(json::value_t type) {
    if (static_cast<int>(frames_.size()) >= limits_.max_depth) {
      error_ = position() + "nested deeper than " + std::to_string(limits_.max_depth) +
               " levels (the limit; " + std::string(limits_.needed) + ")";
      return false;
    }
    Frame f;
    if (!frames_.empty()) {
      const Frame& parent = frames_.back();
      f.path = parent.container->is_object()
                   ? (parent.path.empty() ? "" : parent.path + ".") + parent.key
                   : parent.path + "[]";
    }
    f.container = place(type);
    frames_.push_back(std::move(f));
    return true;
  }
  bool end() {
    frames_.pop_back();
    return true;
  }

  std::string_view text_;
  const char* const* furthest_;
  const Limits& limits_;
  json root_;
  std::vector<Frame> frames_;
  std::string error_;
};

}  // namespace strict

ENDOHAPTICS_DECL json parse_strict(std::string_view text, std::string_view source,
                                   const Limits& limits) {
  const char* furthest = text.data();
  strict::Handler handler(text, &furthest, limits);
  const bool parsed = json::sax_parse(strict::TrackingIterator(text.data(), &furthest),
                                      strict::TrackingIterator(text.data() + text.size(), nullptr),
                                      &handler, json::input_format_t::json, /*strict=*/true,
                                      /*ignore_comments=*/limits.comments);
  if (!parsed) {
    ENDOHAPTICS_THROW(Error(std::string(source) + ": " +
                            (handler.error().empty() ? "not valid JSON" : handler.error())));
  }
  return std::move(handler.root());
}

ENDOHAPTICS_DECL std::string read_bounded(const std::filesystem::path& path, std::size_t max_bytes,
                                          std::string_view what, std::string_view limit) {
  return read_regular_file(path.string(), what, max_bytes, limit);
}

}  // namespace endohaptics::files::detail::json_text
