#include "polysquare/core/work_sharing.h"

#include <algorithm>
#include <numeric>

namespace polysquare {

std::vector<int> item_owners(const std::vector<double>& cost, int processes) {
  const std::size_t n = cost.size();
  std::vector<int> owner(n, 0);
  if (processes <= 1) return owner;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
  std::vector<double> load(static_cast<std::size_t>(processes), 0.0);
  for (std::size_t i : order) {
    const auto least = std::min_element(load.begin(), load.end()) - load.begin();  // first of equal loads
    owner[i] = static_cast<int>(least);
    load[static_cast<std::size_t>(least)] += std::max(cost[i], 0.0);
  }
  return owner;
}

namespace detail {

// 0: no error, 1: MeshingError, 2: InputError, 3: anything else; then the message.
void put_error(ByteWriter& w, const std::exception_ptr& e) {
  if (!e) {
    w.put(std::uint8_t{0});
    return;
  }
  try {
    std::rethrow_exception(e);
  } catch (const MeshingError& x) {
    w.put(std::uint8_t{1});
    w.put(std::string(x.what()));
  } catch (const InputError& x) {
    w.put(std::uint8_t{2});
    w.put(std::string(x.what()));
  } catch (const std::exception& x) {
    w.put(std::uint8_t{3});
    w.put(std::string(x.what()));
  } catch (...) {
    w.put(std::uint8_t{3});
    w.put(std::string("unknown exception"));
  }
}

std::exception_ptr get_error(ByteReader& r) {
  std::uint8_t kind = 0;
  r.get(kind);
  if (kind == 0) return nullptr;
  std::string what;
  r.get(what);
  if (kind == 1) return std::make_exception_ptr(MeshingError(what));
  if (kind == 2) return std::make_exception_ptr(InputError(what));
  return std::make_exception_ptr(std::runtime_error(what));
}

}  // namespace detail
}  // namespace polysquare
