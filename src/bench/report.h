// Markdown tables for the bench: printed to stdout a row at a time as results arrive, and written
// whole into the group's report. A cell we have no value for is an empty string.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "protocol/packet_bits.h"

namespace pms::bench {

struct Column {
  std::string title;
  bool numeric = true;  // right-aligned
  size_t width = 0;     // minimum width while streaming, before the widest cell is known
};

class Table {
 public:
  explicit Table(std::vector<Column> columns);

  // Header and alignment lines for streaming, padded to max(title, Column::width).
  std::string header() const;
  // Adds a row (one cell per column, else pms::Error) and returns its line, padded like header().
  std::string add_row(std::vector<std::string> cells);
  // The whole table, every column as wide as its widest cell.
  std::string markdown() const;
  size_t row_count() const { return rows_.size(); }

 private:
  std::string line(const std::vector<std::string>& cells, const std::vector<size_t>& widths) const;
  std::string rule(const std::vector<size_t>& widths) const;
  std::vector<Column> columns_;
  std::vector<size_t> stream_widths_;
  std::vector<std::vector<std::string>> rows_;
};

std::string thousands(uint64_t value);              // 34772 -> "34,772"
std::string fixed(double value, int decimals);      // fixed(1.234, 2) -> "1.23"
std::string id_bits(uint32_t tree, uint32_t node);  // "<6, 16>", as in kim-lee-kobbelt Table 1

}  // namespace pms::bench
