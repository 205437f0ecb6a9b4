//! @file
//! Plots as PNG through gnuplot (pngcairo), with no path, label or number ever reaching gnuplot
//! as code: the program text is constant apart from decimal integers (sizes, indices), every label
//! and number travels in a data block, and gnuplot runs without a shell in a private folder, its
//! output copied to the requested path by C++ (docs/identification_results.md, "Plots").
//! Configuration time: throws endohaptics::Error (bad figure, gnuplot missing or failing).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>
#include "endohaptics/core/separate_compilation.hpp"

#include "endohaptics/core/error.hpp"

namespace endohaptics::workflow {

//! How a series is drawn.
enum class PlotStyle {
  lines,  //!< a line through the points, broken at gaps and at non-finite values
  boxes,  //!< a filled box per point, `box_width` wide, from the axis to y (a histogram)
};

//! Where a panel's key (the series' titles) goes.
enum class KeyPlacement { top_right, top_left, none };

//! One series of a panel: y over x.
struct PlotSeries {
  std::string title;                   //!< key entry, shown as written (data, never code)
  std::vector<double> x;               //!< abscissae; non-finite: a missing point
  std::vector<double> y;               //!< ordinates, as many as x; non-finite: a missing point
  std::vector<std::size_t> breaks;     //!< indices at which a new line segment starts (gaps)
  PlotStyle style = PlotStyle::lines;  //!< lines, points or boxes
  int line_width = 1;                  //!< 1..10
  double box_width = 1.0;              //!< x units, boxes only; finite and > 0

  //! Appends the point (x, y).
  void add(double x_value, double y_value) {
    x.push_back(x_value);
    y.push_back(y_value);
  }
  //! Breaks the line before the next point added.
  void gap() { breaks.push_back(x.size()); }
};

//! One panel of a figure: axes, labels and the series drawn in it.
struct PlotPanel {
  std::string title;                           //!< above the panel (data, never code)
  std::string x_label;                         //!< (data, never code)
  std::string y_label;                         //!< (data, never code)
  std::vector<PlotSeries> series;              //!< drawn in order
  bool log_y = false;                          //!< logarithmic y axis
  KeyPlacement key = KeyPlacement::top_right;  //!< where the key (legend) goes
};

//! A PNG image of panels stacked top to bottom.
struct PlotFigure {
  std::vector<PlotPanel> panels;  //!< top to bottom
  int width = 1400;               //!< pixels, 200..10000
  int panel_height = 300;         //!< pixels per panel, 100..10000; the image is 100 pixels more
  static constexpr int max_height = 32767;  //!< pixels: cairo's largest image
};

//! `text` as a data-block line may hold it: control characters (C0, DEL, C1) and bytes that are
//! not valid UTF-8 become '?', so no label can break a line or end a data block.
ENDOHAPTICS_DECL std::string plot_text(std::string_view text);

//! The gnuplot program that draws `figure` into "plot.png" in gnuplot's working directory: the
//! commands are constant text and decimal integers; every label is a line of the data block
//! `$text` (each line '|' + plot_text(label)), every number a line of a data block of its series
//! (a number, "NaN" or a blank line at a gap), and every block ends at a line "EOD", which no
//! data line can start with. Throws Error naming the panel and series when the figure is invalid
//! (sizes of x and y, widths, no finite point in a panel, image too large).
ENDOHAPTICS_DECL std::string gnuplot_script(const PlotFigure& figure);

//! Draws `figure` into the PNG file `png` (replaced if present): writes `gnuplot_script(figure)`
//! into a private temporary folder, runs `program` on it there without a shell (posix_spawnp;
//! found on PATH when it has no '/'), checks its exit status and its image, then moves or copies
//! the image to `png`. Throws Error: gnuplot not installed, gnuplot failed (its first error
//! line), no PNG written, or `png` not writable. The temporary folder is removed either way.
ENDOHAPTICS_DECL void write_png(const PlotFigure& figure, const std::filesystem::path& png,
                                const std::string& program = "gnuplot");

}  // namespace endohaptics::workflow

#if !defined(ENDOHAPTICS_SEPARATE_COMPILATION)
#include "endohaptics/workflow/impl/gnuplot.ipp"
#endif
