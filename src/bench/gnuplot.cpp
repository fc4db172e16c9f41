#include "bench/gnuplot.h"

#include <cstdio>
#include <fstream>

#include "bench/child_process.h"
#include "common/error.h"

namespace pms::bench {
namespace {

constexpr double kGnuplotTimeoutSeconds = 60;

// A gnuplot double-quoted string: backslash escapes are processed inside.
std::string quote(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

// Inline data blocks keep the script self-contained: one file to re-run.
std::string data_block(const PlotSeries& s, size_t index) {
  std::string out = "$s" + std::to_string(index) + " << EOD\n";
  for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) out += number(s.x[i]) + " " + number(s.y[i]) + "\n";
  return out + "EOD\n";
}

}  // namespace

std::string gnuplot_script(const Plot& plot, const std::filesystem::path& png_path) {
  // noenhanced: titles are printed as written ("peak_rss" must not turn into a subscript).
  std::string s = "set terminal pngcairo size 960,640 noenhanced font \",11\"\n";
  s += "set output " + quote(png_path.string()) + "\n";
  s += "set title " + quote(plot.title) + "\n";
  s += "set xlabel " + quote(plot.xlabel) + "\n";
  s += "set ylabel " + quote(plot.ylabel) + "\n";
  s += "set grid\nset key top left\n";
  if (plot.log_x) s += "set logscale x\nset format x \"%.0s%c\"\n";  // 100k, 1M, 10M
  if (plot.log_y) s += "set logscale y\n";
  bool right_axis = false;
  for (const PlotSeries& series : plot.series) right_axis |= series.right_axis;
  if (right_axis) {
    s += "set y2label " + quote(plot.y2label) + "\nset ytics nomirror\nset y2tics\n";
    if (plot.log_y) s += "set logscale y2\n";
  }
  std::string command;
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& series = plot.series[i];
    if (series.x.empty()) continue;  // gnuplot stops at an empty data block
    s += data_block(series, i);
    command += command.empty() ? "plot " : ", \\\n     ";
    command += "$s" + std::to_string(i) + " using 1:2 with linespoints pointtype 7 title " + quote(series.title) +
               (series.right_axis ? " axes x1y2" : " axes x1y1");
  }
  return s + command + "\n";
}

std::string plot_png(const Plot& plot, const std::filesystem::path& png_path) {
  bool any = false;
  for (const PlotSeries& series : plot.series) any |= !series.x.empty();
  if (!any) return "no data points to plot";
  if (find_program("gnuplot").empty())
    return "gnuplot is not installed (Debian package gnuplot-nox), so " + png_path.filename().string() +
           " was not drawn";
  std::filesystem::path script_path = png_path;
  script_path.replace_extension(".gp");
  {
    std::ofstream script(script_path);
    script << gnuplot_script(plot, png_path);
    if (!script) fail(script_path.string(), "cannot write");
  }
  ChildOptions options;
  options.timeout_seconds = kGnuplotTimeoutSeconds;
  const ChildResult run = run_child({"gnuplot", script_path.string()}, options);
  if (!run.ok()) return "gnuplot failed on " + script_path.string() + " (" + run.failure() + ")";
  return "";
}

std::string plot_markdown(const std::filesystem::path& dir, const Plot& plot, const std::string& png,
                          const std::string& alt) {
  const std::string skipped = plot_png(plot, dir / png);
  if (skipped.empty()) return "![" + alt + "](" + png + ")\n\n";
  std::fprintf(stderr, "bench: %s\n", skipped.c_str());
  return "No plot " + png + ": " + skipped + ".\n\n";
}

}  // namespace pms::bench
