// Quantized positions on the wire: the grid lives in spm/position_grid.h (the builder codes split records on
// it offline); the protocol layer names it as its own.
#pragma once
#include "spm/position_grid.h"

namespace pms::protocol {

using pms::dequantize_position;
using pms::position_error_bound;
using pms::PositionGrid;
using pms::quantize_position;
using pms::snap_position;
using pms::valid_position_bits;

}  // namespace pms::protocol
