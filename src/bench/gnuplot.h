// Plots through the gnuplot command (Debian package gnuplot-nox) driven by a generated script, so no
// plotting library is linked. The script is kept beside the PNG to re-plot or tweak by hand.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace pms::bench {

struct PlotSeries {
  std::string title;
  std::vector<double> x, y;
  bool right_axis = false;  // plotted against the y2 axis (a second unit on one chart)
};

struct Plot {
  std::string title, xlabel, ylabel, y2label;
  bool log_x = false, log_y = false;  // log_y applies to both y axes
  std::vector<PlotSeries> series;
};

// The script that draws `plot` into `png_path`.
std::string gnuplot_script(const Plot& plot, const std::filesystem::path& png_path);

// Writes the script to PNG_PATH with extension .gp and runs gnuplot on it. Returns an empty string on
// success, else why there is no PNG (gnuplot not installed, or it failed) for the report to print.
std::string plot_png(const Plot& plot, const std::filesystem::path& png_path);

// Draws `plot` into dir/png and returns the report's line for it: the image, or why there is none (also told
// on stderr).
std::string plot_markdown(const std::filesystem::path& dir, const Plot& plot, const std::string& png,
                          const std::string& alt);

}  // namespace pms::bench
