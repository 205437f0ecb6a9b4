//! @file
//! Function bodies of workflow/gnuplot.hpp: included at its end (header-only, the default), or
//! compiled once with ENDOHAPTICS_SEPARATE_COMPILATION (core/separate_compilation.hpp).
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <system_error>

#include "endohaptics/workflow/gnuplot.hpp"

namespace endohaptics::workflow {
namespace detail::gnuplot {

//! The files in gnuplot's private working directory: constant names, the only ones the script
//! names.
inline constexpr const char* script_name = "plot.gp";
inline constexpr const char* image_name = "plot.png";
inline constexpr const char* log_name = "gnuplot.log";
//! Ends every data block; no data line starts with 'E' (labels start with '|', numbers with a
//! digit, '-' or "NaN", gaps are empty).
inline constexpr std::string_view end_of_data = "EOD";

//! `text` cut to `max` bytes, with "..." when cut (for messages).
ENDOHAPTICS_DECL std::string excerpt(std::string_view text, std::size_t max) {
  return text.size() > max ? std::string(text.substr(0, max)) + "..." : std::string(text);
}

//! "panel 2 ('title')" / "panel 2 ('title'), series 1 ('name')", for messages.
ENDOHAPTICS_DECL std::string where(std::size_t panel, const PlotPanel& p) {
  return "panel " + std::to_string(panel + 1) + " ('" + excerpt(plot_text(p.title), 80) + "')";
}
ENDOHAPTICS_DECL std::string where(std::size_t panel, const PlotPanel& p, std::size_t series) {
  return where(panel, p) + ", series " + std::to_string(series + 1) + " ('" +
         excerpt(plot_text(p.series[series].title), 80) + "')";
}

//! Appends `value` as a data field: up to 10 significant digits, or "NaN" when not finite.
ENDOHAPTICS_DECL void append_number(std::string& out, double value) {
  if (!std::isfinite(value)) {
    out += "NaN";
    return;
  }
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value,
                                    std::chars_format::general, 10);
  out.append(buffer.data(), result.ptr);
}

//! The name of the data block of panel `panel`'s series `series` (0-based): "$p1s1", ...
ENDOHAPTICS_DECL std::string block_name(std::size_t panel, std::size_t series) {
  std::string name = "$p";
  name += std::to_string(panel + 1);
  name += 's';
  name += std::to_string(series + 1);
  return name;
}

//! Throws Error unless `figure` can be drawn (see gnuplot_script).
ENDOHAPTICS_DECL void validate(const PlotFigure& figure) {
  using endohaptics::detail::fail;
  if (figure.panels.empty()) fail("plot: the figure has no panel");
  if (figure.width < 200 || figure.width > 10000) {
    fail("plot: width " + std::to_string(figure.width) + " pixels, outside [200, 10000]");
  }
  if (figure.panel_height < 100 || figure.panel_height > 10000) {
    fail("plot: panel height " + std::to_string(figure.panel_height) +
         " pixels, outside [100, 10000]");
  }
  const std::size_t height = figure.panels.size() * static_cast<std::size_t>(figure.panel_height);
  if (height + 100 > static_cast<std::size_t>(PlotFigure::max_height)) {
    fail("plot: " + std::to_string(figure.panels.size()) + " panels of " +
         std::to_string(figure.panel_height) + " pixels make an image " +
         std::to_string(height + 100) + " pixels high, more than cairo's " +
         std::to_string(PlotFigure::max_height));
  }
  for (std::size_t p = 0; p < figure.panels.size(); ++p) {
    const PlotPanel& panel = figure.panels[p];
    if (panel.series.empty()) fail("plot: " + where(p, panel) + " has no series");
    bool any_point = false;
    for (std::size_t s = 0; s < panel.series.size(); ++s) {
      const PlotSeries& series = panel.series[s];
      if (series.x.size() != series.y.size()) {
        fail("plot: " + where(p, panel, s) + ": " + std::to_string(series.x.size()) +
             " x values but " + std::to_string(series.y.size()) + " y values");
      }
      if (series.line_width < 1 || series.line_width > 10) {
        fail("plot: " + where(p, panel, s) + ": line width " + std::to_string(series.line_width) +
             ", outside [1, 10]");
      }
      if (series.style == PlotStyle::boxes &&
          !(std::isfinite(series.box_width) && series.box_width > 0.0)) {
        fail("plot: " + where(p, panel, s) + ": box width " +
             endohaptics::detail::format_number(series.box_width) + ", expected > 0");
      }
      for (std::size_t k = 0; k < series.x.size() && !any_point; ++k) {
        any_point = std::isfinite(series.x[k]) && std::isfinite(series.y[k]);
      }
    }
    if (!any_point) fail("plot: " + where(p, panel) + " has no finite point to draw");
  }
}

//! The first line of gnuplot's messages that says why it failed ("line 7: ..."), else its first
//! line that is not a warning, as plot_text and at most 300 bytes; "no message" if none.
ENDOHAPTICS_DECL std::string first_error(std::string_view log) {
  const std::string prefix = std::string("\"") + script_name + "\" ";
  std::string fallback;
  while (!log.empty()) {
    const std::size_t end = std::min(log.find('\n'), log.size());
    std::string_view line = log.substr(0, end);
    log.remove_prefix(std::min(end + 1, log.size()));
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
    if (line.empty() || line.find_first_not_of("^ ") == std::string_view::npos ||
        line.find("warning:") != std::string_view::npos ||
        line.find("Warning:") != std::string_view::npos) {
      continue;
    }
    if (line.starts_with(prefix)) return excerpt(plot_text(line.substr(prefix.size())), 300);
    if (fallback.empty()) fallback = excerpt(plot_text(line), 300);
  }
  return fallback.empty() ? "no message" : fallback;
}

//! A folder only this process may use (mkdtemp, mode 0700), removed with its content at scope
//! exit.
class PrivateFolder {
 public:
  PrivateFolder() {
    std::error_code ec;
    std::filesystem::path base = std::filesystem::temp_directory_path(ec);
    if (ec) base = "/tmp";
    std::string name = (base / "endohaptics-plot-XXXXXX").string();
    if (::mkdtemp(name.data()) == nullptr) {
      const int error = errno;
      endohaptics::detail::fail("plot: cannot create a temporary folder in '" + base.string() +
                                "': " + std::strerror(error));
    }
    path_ = name;
  }
  ~PrivateFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  PrivateFolder(const PrivateFolder&) = delete;
  PrivateFolder& operator=(const PrivateFolder&) = delete;

  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
};

//! posix_spawn_file_actions_t, destroyed at scope exit.
class FileActions {
 public:
  FileActions() { ::posix_spawn_file_actions_init(&actions_); }
  ~FileActions() { ::posix_spawn_file_actions_destroy(&actions_); }
  FileActions(const FileActions&) = delete;
  FileActions& operator=(const FileActions&) = delete;

  [[nodiscard]] posix_spawn_file_actions_t* get() noexcept { return &actions_; }

 private:
  posix_spawn_file_actions_t actions_{};
};

//! At most `max` bytes of the file at `path` (empty if it cannot be read).
ENDOHAPTICS_DECL std::string read_start(const std::filesystem::path& path, std::size_t max) {
  std::ifstream in(path, std::ios::binary);
  std::string text(max, '\0');
  in.read(text.data(), static_cast<std::streamsize>(max));
  text.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return text;
}

}  // namespace detail::gnuplot

ENDOHAPTICS_DECL std::string plot_text(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) {
      out += '?';
      ++i;
      continue;
    }
    if (c < 0x80) {
      out += static_cast<char>(c);
      ++i;
      continue;
    }
    // A multi-byte sequence: its length and the range of its second byte (RFC 3629, table 3-7
    // of the Unicode standard: no overlong forms, no surrogates, nothing above U+10FFFF).
    std::size_t length = 0;
    unsigned char low = 0x80;
    unsigned char high = 0xbf;
    if (c >= 0xc2 && c <= 0xdf) {
      length = 2;
    } else if (c == 0xe0) {
      length = 3;
      low = 0xa0;
    } else if ((c >= 0xe1 && c <= 0xec) || c == 0xee || c == 0xef) {
      length = 3;
    } else if (c == 0xed) {
      length = 3;
      high = 0x9f;
    } else if (c == 0xf0) {
      length = 4;
      low = 0x90;
    } else if (c >= 0xf1 && c <= 0xf3) {
      length = 4;
    } else if (c == 0xf4) {
      length = 4;
      high = 0x8f;
    }
    bool valid = length > 0 && i + length <= text.size();
    for (std::size_t k = 1; valid && k < length; ++k) {
      const auto b = static_cast<unsigned char>(text[i + k]);
      valid = k == 1 ? (b >= low && b <= high) : (b >= 0x80 && b <= 0xbf);
    }
    if (!valid) {
      out += '?';  // one byte at a time: the next one may start a valid character
      ++i;
      continue;
    }
    // The C1 controls U+0080..U+009F (C2 80..C2 9F) are control characters too.
    if (c == 0xc2 && static_cast<unsigned char>(text[i + 1]) < 0xa0) {
      out += '?';
      i += 2;
      continue;
    }
    out.append(text.substr(i, length));
    i += length;
  }
  return out;
}

ENDOHAPTICS_DECL std::string gnuplot_script(const PlotFigure& figure) {
  namespace gp = detail::gnuplot;
  gp::validate(figure);
  const std::string eod(gp::end_of_data);
  const std::size_t height =
      figure.panels.size() * static_cast<std::size_t>(figure.panel_height) + 100;
  std::string script =
      "# endohaptics (workflow/gnuplot.hpp): the commands are constant text and integers; every\n"
      "# label and number is a line of a data block.\n"
      "set encoding utf8\n"
      "set terminal pngcairo size " +
      std::to_string(figure.width) + "," + std::to_string(height) +
      " noenhanced\n"
      "set output '" +
      gp::image_name +
      "'\n"
      "set datafile separator whitespace\n";

  // The labels, in the order the commands below use them: $text[i] is "|" + the label.
  script += "$text << " + eod + "\n";
  std::size_t lines = 0;
  const auto add_text = [&](std::string_view label) {
    script += '|';
    script += plot_text(label);
    script += '\n';
    return ++lines;
  };
  std::vector<std::string> commands;
  const auto text = [](std::size_t line) {
    std::string expression = "$text[";
    expression += std::to_string(line);
    expression += "][2:]";
    return expression;
  };
  for (std::size_t p = 0; p < figure.panels.size(); ++p) {
    const PlotPanel& panel = figure.panels[p];
    std::string c = "set title " + text(add_text(panel.title)) + "\n";
    c += "set xlabel " + text(add_text(panel.x_label)) + "\n";
    c += "set ylabel " + text(add_text(panel.y_label)) + "\n";
    c += panel.log_y ? "set logscale y\n" : "unset logscale y\n";
    switch (panel.key) {
      case KeyPlacement::top_right:
        c += "set key top right\n";
        break;
      case KeyPlacement::top_left:
        c += "set key top left\n";
        break;
      case KeyPlacement::none:
        c += "unset key\n";
        break;
    }
    c += "plot ";
    for (std::size_t s = 0; s < panel.series.size(); ++s) {
      const PlotSeries& series = panel.series[s];
      const std::string block = gp::block_name(p, s);
      c += s > 0 ? ", " : "";
      c += block +
           (series.style == PlotStyle::boxes ? " using 1:2:3 with boxes" : " using 1:2 with lines");
      c += " lw " + std::to_string(series.line_width) + " title " + text(add_text(series.title));
    }
    commands.push_back(c + "\n");
  }
  script += eod + "\n";

  // The numbers: one block per series, "x y" (boxes: "x y width") per line, a blank line before
  // each break.
  for (std::size_t p = 0; p < figure.panels.size(); ++p) {
    for (std::size_t s = 0; s < figure.panels[p].series.size(); ++s) {
      const PlotSeries& series = figure.panels[p].series[s];
      std::vector<std::size_t> breaks = series.breaks;
      std::sort(breaks.begin(), breaks.end());
      auto next_break = breaks.begin();
      script += gp::block_name(p, s);
      script += " << " + eod + "\n";
      for (std::size_t k = 0; k < series.x.size(); ++k) {
        bool gap = false;
        while (next_break != breaks.end() && *next_break <= k) {
          gap = gap || (*next_break == k && k > 0);
          ++next_break;
        }
        if (gap) script += "\n";
        gp::append_number(script, series.x[k]);
        script += " ";
        gp::append_number(script, series.y[k]);
        if (series.style == PlotStyle::boxes) {
          script += " ";
          gp::append_number(script, series.box_width);
        }
        script += "\n";
      }
      script += eod + "\n";
    }
  }

  script += "set multiplot layout " + std::to_string(figure.panels.size()) +
            ",1\n"
            "set grid\n"
            "set style fill solid 0.6\n";
  for (const std::string& c : commands) script += c;
  script += "unset multiplot\n";
  return script;
}

ENDOHAPTICS_DECL void write_png(const PlotFigure& figure, const std::filesystem::path& png,
                                const std::string& program) {
  namespace gp = detail::gnuplot;
  using endohaptics::detail::fail;
  const std::string target = "plot '" + png.string() + "'";
  const std::string script = gnuplot_script(figure);
  const gp::PrivateFolder folder;
  {
    std::ofstream out(folder.path() / gp::script_name, std::ios::binary);
    out << script;
    out.close();
    if (!out) fail(target + ": cannot write the gnuplot script in " + folder.path().string());
  }

  // gnuplot runs in the private folder (no shell): stdin /dev/null, stdout and stderr to a file
  // there (no pipe to fill or break), its one argument the script's constant name.
  gp::FileActions actions;
  const std::string folder_name = folder.path().string();
  if (::posix_spawn_file_actions_addchdir_np(actions.get(), folder_name.c_str()) != 0 ||
      ::posix_spawn_file_actions_addopen(actions.get(), 0, "/dev/null", O_RDONLY, 0) != 0 ||
      ::posix_spawn_file_actions_addopen(actions.get(), 1, gp::log_name,
                                         O_WRONLY | O_CREAT | O_TRUNC, 0600) != 0 ||
      ::posix_spawn_file_actions_adddup2(actions.get(), 1, 2) != 0) {
    fail(target + ": cannot prepare to run gnuplot (out of memory)");
  }
  std::string arg0 = program;
  std::string arg1 = gp::script_name;
  std::array<char*, 3> argv{arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int spawned =
      ::posix_spawnp(&pid, program.c_str(), actions.get(), nullptr, argv.data(), environ);
  if (spawned == ENOENT) {
    fail(target + ": " +
         (program == "gnuplot" ? std::string("gnuplot is not installed or not on PATH")
                               : "'" + program + "' was not found") +
         " (Debian: apt-get install gnuplot-nox)");
  }
  if (spawned != 0) {
    fail(target + ": cannot run '" + program + "': " + std::strerror(spawned));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    const int error = errno;
    if (error != EINTR) fail(target + ": waiting for gnuplot failed: " + std::strerror(error));
  }
  const std::string log = gp::read_start(folder.path() / gp::log_name, 64 * 1024);
  if (WIFSIGNALED(status)) {
    fail(target + ": gnuplot was ended by signal " + std::to_string(WTERMSIG(status)) + ": " +
         gp::first_error(log));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    fail(target + ": gnuplot failed (exit status " + std::to_string(WEXITSTATUS(status)) +
         "): " + gp::first_error(log));
  }
  const std::filesystem::path image = folder.path() / gp::image_name;
  constexpr std::string_view png_signature("\x89PNG\r\n\x1a\n", 8);
  if (gp::read_start(image, png_signature.size()) != png_signature) {
    fail(target + ": gnuplot exited without writing a PNG image (" + gp::first_error(log) + ")");
  }

  // Into place: a rename when on the same file system, else a copy.
  std::error_code ec;
  std::filesystem::rename(image, png, ec);
  if (ec) {
    std::error_code copy_ec;
    std::filesystem::copy_file(image, png, std::filesystem::copy_options::overwrite_existing,
                               copy_ec);
    if (copy_ec) fail(target + ": cannot write it: " + copy_ec.message());
  }
  std::error_code size_ec;
  const auto size = std::filesystem::file_size(png, size_ec);
  if (size_ec || size == 0) {
    fail(target + ": not written" + (size_ec ? ": " + size_ec.message() : std::string(" (empty)")));
  }
}

}  // namespace endohaptics::workflow
