#include "bench/report.h"

#include <algorithm>
#include <cstdio>

#include "common/error.h"
#include "protocol/packet_bits.h"

namespace pms::bench {
namespace {

// Columns line up on screen only if padding counts characters, not UTF-8 bytes ("µs").
size_t display_width(const std::string& text) {
  return size_t(std::count_if(text.begin(), text.end(), [](char c) { return (uint8_t(c) & 0xC0) != 0x80; }));
}

std::string pad(const std::string& text, size_t width, bool right) {
  const size_t used = display_width(text);
  if (used >= width) return text;
  const std::string fill(width - used, ' ');
  return right ? fill + text : text + fill;
}

// A '|' inside a cell would end it.
std::string escape_cell(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

Table::Table(std::vector<Column> columns) : columns_(std::move(columns)) {
  for (Column& c : columns_) c.title = escape_cell(c.title);
  for (const Column& c : columns_) stream_widths_.push_back(std::max(c.width, display_width(c.title)));
}

std::string Table::line(const std::vector<std::string>& cells, const std::vector<size_t>& widths) const {
  std::string out = "|";
  for (size_t i = 0; i < cells.size(); ++i) {
    out += ' ';
    out += pad(cells[i], widths[i], columns_[i].numeric);
    out += " |";
  }
  return out + "\n";
}

std::string Table::rule(const std::vector<size_t>& widths) const {
  std::string out = "|";
  for (size_t i = 0; i < columns_.size(); ++i) {
    // Markdown wants at least three dashes; ':' on the right marks a right-aligned column.
    const size_t dashes = std::max<size_t>(widths[i], 3);
    out += ' ';
    out.append(columns_[i].numeric ? dashes - 1 : dashes, '-');
    out += columns_[i].numeric ? ": |" : " |";
  }
  return out + "\n";
}

std::string Table::header() const {
  std::vector<std::string> titles;
  for (const Column& c : columns_) titles.push_back(c.title);
  return line(titles, stream_widths_) + rule(stream_widths_);
}

std::string Table::add_row(std::vector<std::string> cells) {
  if (cells.size() != columns_.size())
    fail("report table", "row has " + std::to_string(cells.size()) + " cells, the table has " +
                             std::to_string(columns_.size()) + " columns");
  for (std::string& cell : cells) cell = escape_cell(cell);
  rows_.push_back(std::move(cells));
  return line(rows_.back(), stream_widths_);
}

std::string Table::markdown() const {
  std::vector<size_t> widths;
  std::vector<std::string> titles;
  for (const Column& c : columns_) {
    widths.push_back(std::max<size_t>(display_width(c.title), 3));
    titles.push_back(c.title);
  }
  for (const auto& row : rows_)
    for (size_t i = 0; i < row.size(); ++i) widths[i] = std::max(widths[i], display_width(row[i]));
  std::string out = line(titles, widths) + rule(widths);
  for (const auto& row : rows_) out += line(row, widths);
  return out;
}

std::string thousands(uint64_t value) {
  const std::string digits = std::to_string(value);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

std::string id_bits(uint32_t tree, uint32_t node) {
  char text[32];
  std::snprintf(text, sizeof text, "<%u, %u>", tree, node);
  return text;
}

}  // namespace pms::bench
