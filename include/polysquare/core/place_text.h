// Places in message texts: the "(x, y)" that at_text and point_text write, found again in a finished message and
// written anew (in another frame or CRS) by whoever prints it.
#pragma once

#include <functional>
#include <string>

#include "polysquare/core/geometry.h"

namespace polysquare {

/// Writes a place as message text, e.g. "(x, y)" in the input's own coordinates.
using PlaceWriter = std::function<std::string(Vec2)>;

/// `text` with every place in it written by `write`. A place is "(x, y)": two finite decimal numbers (fixed or
/// exponent notation, as at_text, point_text and short_number write them) in parentheses, separated by ", ",
/// at least one of them with a decimal point or an exponent; a pair of integers ("at (3, 5)", a lattice point
/// of quantize's messages) is no place. Anything else stays byte for byte. For texts whose places are known
/// only as text where they are printed: errors thrown from worker threads, reasons kept in the report.
std::string rewrite_places(const std::string& text, const PlaceWriter& write);

}  // namespace polysquare
