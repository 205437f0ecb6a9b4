#include "endohaptics/workflow/gnuplot.hpp"

#include <doctest/doctest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "test_support.hpp"

// Hostile file names (docs/safety.md): a log named `run';system "touch INJECTED";print '.csv` ran
// `touch` through the plots of endohaptics-replay and endohaptics-force-report, which spliced paths
// and labels into gnuplot commands. Here no label, path or number reaches gnuplot as code.
namespace workflow_gnuplot_test {

using endohaptics::test::message_of;
using endohaptics::test::TempDir;

namespace {

namespace wf = endohaptics::workflow;
namespace fs = std::filesystem;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Labels that ended the old scripts' quoted strings, commands or lines, or that could end a data
// block or look like gnuplot syntax (macros, backquotes, data block names).
std::vector<std::string> hostile_labels(const std::string& marker) {
  return {"run';system \"touch " + marker + "\";print '.csv",
          "x\";system \"touch " + marker + "\";print \"",
          "line\nsystem \"touch " + marker + "\"\nend",
          "EOD",
          "EOD\nsystem \"touch " + marker + "\"",
          "\r\nEOD\r\n",
          std::string("nul\0system \"touch ", 18) + marker + "\"",
          "back\\slash\\",
          "`touch " + marker + "`",
          "@macro $text[1] $p1s1",
          "ünïcödé ✓ 𝄞, invalid \xff\xfe",
          ""};
}

// A figure of `panels` panels whose labels are taken in turn from `labels` and whose values are
// `scale` times a fixed pattern (NaN, infinities and gaps included).
wf::PlotFigure figure_of(const std::vector<std::string>& labels, double scale, int panels = 2) {
  std::size_t next = 0;
  const auto label = [&] { return labels[next++ % labels.size()]; };
  wf::PlotFigure figure;
  for (int p = 0; p < panels; ++p) {
    wf::PlotPanel panel;
    panel.title = label();
    panel.x_label = label();
    panel.y_label = label();
    panel.key = p == 0 ? wf::KeyPlacement::top_left : wf::KeyPlacement::top_right;
    for (int s = 0; s < 3; ++s) {
      wf::PlotSeries series;
      series.title = label();
      series.line_width = 1 + s;
      for (int k = 0; k < 40; ++k) {
        if (k == 20) series.gap();
        const double t = 0.01 * k;
        series.add(t, k == 7   ? std::numeric_limits<double>::quiet_NaN()
                      : k == 8 ? std::numeric_limits<double>::infinity()
                      : k == 9 ? -std::numeric_limits<double>::infinity()
                               : scale * std::sin(t + s));
      }
      panel.series.push_back(std::move(series));
    }
    figure.panels.push_back(std::move(panel));
  }
  wf::PlotPanel histogram;
  histogram.title = label();
  histogram.log_y = true;
  histogram.key = wf::KeyPlacement::none;
  wf::PlotSeries boxes;
  boxes.title = label();
  boxes.style = wf::PlotStyle::boxes;
  boxes.box_width = 5.0 * scale;
  for (int k = 0; k < 10; ++k) boxes.add(5.0 * k * scale, 1.0 + k * k);
  histogram.series.push_back(std::move(boxes));
  figure.panels.push_back(std::move(histogram));
  return figure;
}

// A gnuplot script read as gnuplot reads it: a line `$name << EOD` starts a data block, which
// ends at the first line that starts with "EOD" (gnuplot's datablock_command compares the start
// of each line with the terminator). Everything else is a command.
struct ParsedScript {
  std::vector<std::string> commands;
  std::map<std::string, std::vector<std::string>> blocks;
  bool unterminated = false;
};

ParsedScript parse(const std::string& script) {
  ParsedScript out;
  std::istringstream in(script);
  std::string line;
  std::optional<std::string> block;
  while (std::getline(in, line)) {
    if (block) {
      if (line.starts_with("EOD")) {
        block.reset();
      } else {
        out.blocks[*block].push_back(line);
      }
      continue;
    }
    const auto start = line.find(" << EOD");
    if (line.starts_with("$") && start != std::string::npos && line.ends_with(" << EOD")) {
      block = line.substr(0, start);
      out.blocks[*block];
      continue;
    }
    out.commands.push_back(line);
  }
  out.unterminated = block.has_value();
  return out;
}

// Every label of `figure` in the order gnuplot_script lists them in $text.
std::vector<std::string> labels_in_order(const wf::PlotFigure& figure) {
  std::vector<std::string> out;
  for (const auto& panel : figure.panels) {
    out.push_back(panel.title);
    out.push_back(panel.x_label);
    out.push_back(panel.y_label);
    for (const auto& series : panel.series) out.push_back(series.title);
  }
  return out;
}

// A number field as the script writes it: "NaN" or a whole finite number.
bool is_number_field(const std::string& field) {
  if (field == "NaN") return true;
  std::size_t used = 0;
  try {
    const double v = std::stod(field, &used);
    return used == field.size() && std::isfinite(v);
  } catch (const std::exception&) {
    return false;
  }
}

// Whether an executable `name` is on PATH.
bool on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = dirs.substr(start, end - start);
    if (!dir.empty() && ::access((fs::path(dir) / name).c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

// Sets an environment variable for the scope (CTest runs each test case in its own process; a
// run of the whole executable gets the old value back).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// An executable shell script standing in for gnuplot.
std::string fake_gnuplot(const TempDir& dir, const std::string& name, const std::string& body) {
  const std::string path = dir.write(name, "#!/bin/sh\n" + body + "\n");
  fs::permissions(path, fs::perms::owner_all);
  return path;
}

bool is_png(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(8, '\0');
  in.read(head.data(), 8);
  return in.gcount() == 8 && head == std::string("\x89PNG\r\n\x1a\n", 8);
}

// The names of every file under `dir`, recursively.
std::vector<std::string> files_under(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    out.push_back(entry.path().lexically_relative(dir).string());
  }
  return out;
}

}  // namespace

TEST_CASE("plot_text: control characters and invalid UTF-8 become '?', other text stays") {
  CHECK(wf::plot_text("run';system \"touch X\";print '.csv") ==
        "run';system \"touch X\";print '.csv");
  CHECK(wf::plot_text(std::string("a\nb\rc\td\0e\x1b[1m\x7f", 14)) == "a?b?c?d?e?[1m?");
  CHECK(wf::plot_text("ünïcödé ✓ 𝄞 Ω") == "ünïcödé ✓ 𝄞 Ω");
  CHECK(wf::plot_text("\xff\xfe") == "??");
  CHECK(wf::plot_text("cut \xc3") == "cut ?");  // a sequence cut short
  CHECK(wf::plot_text("\xc3"
                      "A") == "?A");                        // a lead byte, then ASCII
  CHECK(wf::plot_text("\xc0\xaf") == "??");                 // overlong '/'
  CHECK(wf::plot_text("\xed\xa0\x80") == "???");            // a UTF-16 surrogate
  CHECK(wf::plot_text("\xf4\x90\x80\x80") == "????");       // above U+10FFFF
  CHECK(wf::plot_text("next\xc2\x85line") == "next?line");  // NEL, a C1 control
  CHECK(wf::plot_text("\xe2\x80\xa8") == "\xe2\x80\xa8");   // U+2028: not a line to gnuplot
}

TEST_CASE("gnuplot_script: every label and number is data, the commands are the figure's shape") {
  const std::vector<std::string> labels = hostile_labels("/tmp/INJECTED");
  const wf::PlotFigure figure = figure_of(labels, 1.0);
  const std::string script = wf::gnuplot_script(figure);
  const ParsedScript parsed = parse(script);
  REQUIRE_FALSE(parsed.unterminated);

  // Each label is one line of $text, whole ('|' + plot_text(label)), in order: none ended the
  // block or added a line.
  const std::vector<std::string> expected = labels_in_order(figure);
  REQUIRE(parsed.blocks.contains("$text"));
  const std::vector<std::string>& text = parsed.blocks.at("$text");
  REQUIRE(text.size() == expected.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    CAPTURE(i);
    CHECK(text[i] == "|" + wf::plot_text(expected[i]));
  }
  // Every other block holds numbers only: "x y" ("x y width" for boxes), NaN, or a blank line.
  std::size_t number_lines = 0, blank_lines = 0;
  for (const auto& [name, lines] : parsed.blocks) {
    if (name == "$text") continue;
    for (const std::string& line : lines) {
      if (line.empty()) {
        ++blank_lines;
        continue;
      }
      std::istringstream fields(line);
      std::string field;
      int count = 0;
      while (fields >> field) {
        CAPTURE(line);
        CHECK(is_number_field(field));
        ++count;
      }
      CHECK((count == 2 || count == 3));
      ++number_lines;
    }
  }
  CHECK(number_lines == 2 * 3 * 40 + 10);  // two panels of three series, one histogram
  CHECK(blank_lines == 2 * 3);             // one gap per line series
  CHECK(contains(script, "\n0.07 NaN\n0.08 NaN\n0.09 NaN\n"));  // NaN and both infinities

  // No label text outside the data blocks.
  std::string commands;
  for (const std::string& c : parsed.commands) commands += c + "\n";
  for (const char* fragment : {"touch", "system", "INJECTED", "run'", "ünï", "macro", "slash"}) {
    CAPTURE(fragment);
    CHECK_FALSE(contains(commands, fragment));
  }
  // The labels reach gnuplot only as strings read from $text.
  CHECK(contains(commands, "set title $text[1][2:]"));
  CHECK(contains(commands, "title $text[4][2:]"));

  // The commands depend on the figure's shape only: other labels and other numbers, the same
  // commands, byte for byte.
  const std::string plain = wf::gnuplot_script(figure_of({"a", "b", "c"}, 1e6));
  CHECK(parse(plain).commands == parsed.commands);
  CHECK(parse(plain).commands != parse(wf::gnuplot_script(figure_of(labels, 1.0, 3))).commands);
}

TEST_CASE("gnuplot_script: an invalid figure is refused, naming its panel and series") {
  wf::PlotFigure figure = figure_of({"forces", "t", "F", "truth"}, 1.0, 1);
  CHECK_NOTHROW((void)wf::gnuplot_script(figure));

  wf::PlotFigure bad = figure;
  bad.panels[0].series[1].y.pop_back();
  CHECK(message_of([&] { (void)wf::gnuplot_script(bad); }) ==
        "plot: panel 1 ('forces'), series 2 ('forces'): 40 x values but 39 y values");
  bad = figure;
  bad.panels[0].series[0].line_width = 0;
  CHECK(contains(message_of([&] { (void)wf::gnuplot_script(bad); }), "line width 0, outside"));
  bad = figure;
  bad.panels[1].series[0].box_width = 0.0;
  CHECK(contains(message_of([&] { (void)wf::gnuplot_script(bad); }), "panel 2 ('F'), series 1"));
  bad = figure;
  for (auto& series : bad.panels[0].series) {
    for (double& y : series.y) y = std::numeric_limits<double>::quiet_NaN();
  }
  CHECK(message_of([&] { (void)wf::gnuplot_script(bad); }) ==
        "plot: panel 1 ('forces') has no finite point to draw");
  bad = figure;
  bad.panels[0].series.clear();
  CHECK(contains(message_of([&] { (void)wf::gnuplot_script(bad); }), "has no series"));
  CHECK(message_of([] { (void)wf::gnuplot_script(wf::PlotFigure{}); }) ==
        "plot: the figure has no panel");
  bad = figure;
  bad.panels.resize(110, figure.panels[0]);
  CHECK(contains(message_of([&] { (void)wf::gnuplot_script(bad); }),
                 "110 panels of 300 pixels make an image 33100 pixels high"));
  bad = figure;
  bad.width = 50;
  CHECK(contains(message_of([&] { (void)wf::gnuplot_script(bad); }), "width 50 pixels"));
}

TEST_CASE("write_png: hostile labels, paths and temporary folder plot, and nothing runs" *
          doctest::skip(!on_path("gnuplot"))) {
  const TempDir dir("gnuplot");
  const std::string marker = (dir.path() / "INJECTED").string();
  // Names that would run `touch INJECTED` in `dir` from gnuplot's folder (two levels below it)
  // if they reached a command. The private folder is made under TMPDIR: one such name.
  const std::string hostile = "';system \"cd ..;cd ..;touch INJECTED\";print '";
  const fs::path tmp = dir.path() / ("tmp" + hostile);
  fs::create_directories(tmp);
  const ScopedEnv tmpdir("TMPDIR", tmp.string());
  const fs::path out = dir.path() / ("out" + hostile);
  fs::create_directories(out);
  const fs::path png = out / ("fit" + hostile + ".png");

  wf::write_png(figure_of(hostile_labels(marker), 1.0), png);
  CHECK(is_png(png));
  CHECK(fs::file_size(png) > 1000);
  // Nothing but the image: no INJECTED file anywhere, no data file beside it, the private folder
  // removed.
  CHECK(files_under(dir.path()).size() == 3);  // tmp..., out..., out.../fit....png
  CHECK_FALSE(fs::exists(marker));
  CHECK(fs::is_empty(tmp));

  // Replaced when it exists.
  const auto before = fs::file_size(png);
  wf::write_png(figure_of({"a"}, 2.0, 1), png);
  CHECK(is_png(png));
  CHECK(fs::file_size(png) != before);
}

TEST_CASE("write_png: gnuplot missing or failing is an error that says why") {
  const TempDir dir("gnuplot-fake");
  const wf::PlotFigure figure = figure_of({"a"}, 1.0, 1);
  const fs::path png = dir.path() / "plot.png";

  // Not installed: gnuplot not on PATH, or a program that does not exist.
  {
    const TempDir empty("empty-path");
    const ScopedEnv path("PATH", empty.path().string());
    CHECK(message_of([&] { wf::write_png(figure, png); }) ==
          "plot '" + png.string() +
              "': gnuplot is not installed or not on PATH (Debian: apt-get install gnuplot-nox)");
  }
  const std::string missing = (dir.path() / "no-gnuplot").string();
  CHECK(contains(message_of([&] { wf::write_png(figure, png, missing); }),
                 "'" + missing + "' was not found"));

  // Fails: exit status and gnuplot's first error line (not its warnings or the echoed command).
  const std::string failing =
      fake_gnuplot(dir, "failing",
                   "echo 'plot $p1s1 using 1:2' >&2\n"
                   "echo '\"plot.gp\" line 2: warning: empty range' >&2\n"
                   "echo '\"plot.gp\" line 12: unrecognized plot type' >&2\n"
                   "exit 3");
  CHECK(message_of([&] { wf::write_png(figure, png, failing); }) ==
        "plot '" + png.string() +
            "': gnuplot failed (exit status 3): line 12: unrecognized plot type");
  const std::string killed = fake_gnuplot(dir, "killed", "kill -9 $$");
  CHECK(contains(message_of([&] { wf::write_png(figure, png, killed); }), "ended by signal 9"));

  // Exits 0 without an image, or with something that is not a PNG: an error, not a success.
  const std::string silent = fake_gnuplot(dir, "silent", "exit 0");
  CHECK(contains(message_of([&] { wf::write_png(figure, png, silent); }),
                 "gnuplot exited without writing a PNG image"));
  const std::string text = fake_gnuplot(dir, "text", "echo hello > plot.png");
  CHECK(contains(message_of([&] { wf::write_png(figure, png, text); }),
                 "gnuplot exited without writing a PNG image"));
  CHECK_FALSE(fs::exists(png));

  // A stand-in that checks how it is run: in its private folder, the script's constant name as its
  // only argument, stdin empty; it writes a PNG signature.
  const std::string checking =
      fake_gnuplot(dir, "checking",
                   "[ $# -eq 1 ] && [ \"$1\" = plot.gp ] && [ -f plot.gp ] || exit 9\n"
                   "grep -q \"^set output 'plot.png'$\" plot.gp || exit 8\n"
                   "[ -z \"$(cat)\" ] || exit 7\n"
                   "printf '\\211PNG\\r\\n\\032\\n' > plot.png");
  wf::write_png(figure, png, checking);
  CHECK(is_png(png));
  // The image cannot be put where asked.
  CHECK(contains(message_of([&] { wf::write_png(figure, dir.path() / "no" / "x.png", checking); }),
                 "x.png': cannot write it: "));
}

}  // namespace workflow_gnuplot_test
