#include "polysquare/core/place_text.h"

#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>

namespace polysquare {
namespace {

struct Number {
  double value = 0;
  bool integer = true;  ///< written without a decimal point or an exponent
  std::size_t end = 0;  ///< index after its last character
};

// The number starting at text[at] (from_chars: no leading '+' or blank, as the place writers write none).
std::optional<Number> number_at(std::string_view text, std::size_t at) {
  Number n;
  const char* first = text.data() + at;
  const auto [ptr, ec] = std::from_chars(first, text.data() + text.size(), n.value);
  if (ec != std::errc() || !std::isfinite(n.value)) return std::nullopt;
  n.integer = std::string_view(first, static_cast<std::size_t>(ptr - first)).find_first_of(".eE") == std::string_view::npos;
  n.end = static_cast<std::size_t>(ptr - text.data());
  return n;
}

// The place "(x, y)" whose '(' is text[open]: the point and the index after its ')'.
std::optional<std::pair<Vec2, std::size_t>> place_at(std::string_view text, std::size_t open) {
  const std::optional<Number> x = number_at(text, open + 1);
  if (!x || text.substr(x->end, 2) != ", ") return std::nullopt;
  const std::optional<Number> y = number_at(text, x->end + 2);
  if (!y || y->end >= text.size() || text[y->end] != ')' || (x->integer && y->integer)) return std::nullopt;
  return std::pair{Vec2{x->value, y->value}, y->end + 1};
}

}  // namespace

std::string rewrite_places(const std::string& text, const PlaceWriter& write) {
  std::string out;
  std::size_t done = 0;
  for (std::size_t open = text.find('('); open != std::string::npos; open = text.find('(', open + 1)) {
    const auto place = place_at(text, open);
    if (!place) continue;
    out.append(text, done, open - done).append(write(place->first));
    done = place->second;
    open = done - 1;
  }
  return out.append(text, done, std::string::npos);
}

}  // namespace polysquare
