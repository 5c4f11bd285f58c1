// Work shared between processes (core/work_sharing.h): bytes that round-trip, a balanced and deterministic
// assignment, and shared_for's contract, with processes simulated by threads that exchange through a barrier.
#include <gtest/gtest.h>

#include <barrier>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/core/work_sharing.h"

using namespace polysquare;

namespace {

// P "processes" in one: each thread holds a ThreadSharing of its rank; all_gather deposits this rank's items,
// waits for the others, then copies every other owner's.
struct Exchange {
  explicit Exchange(int p) : processes(p), slots(static_cast<std::size_t>(p)), sync(p) {}
  int processes;
  std::vector<std::vector<std::string>> slots;
  std::barrier<> sync;
};

class ThreadSharing final : public WorkSharing {
 public:
  ThreadSharing(Exchange& x, int rank) : x_(x), rank_(rank) {}
  int processes() const override { return x_.processes; }
  int rank() const override { return rank_; }
  void all_gather(std::vector<std::string>& items, const std::vector<int>& owner, std::string_view) const override {
    x_.slots[static_cast<std::size_t>(rank_)] = items;
    x_.sync.arrive_and_wait();
    for (std::size_t i = 0; i < items.size(); ++i)
      if (owner[i] != rank_) items[i] = x_.slots[static_cast<std::size_t>(owner[i])][i];
    x_.sync.arrive_and_wait();  // nobody overwrites a slot before all have read
  }

 private:
  Exchange& x_;
  int rank_;
};

}  // namespace

TEST(WorkSharing, BytesRoundTripAndATruncatedItemIsRefused) {
  std::string bytes;
  ByteWriter w(bytes);
  const std::vector<Vec2> points{{1.5, -2.0}, {1e300, 3e-300}};
  const std::vector<std::vector<int>> nested{{1, 2, 3}, {}, {7}};
  w.put(std::int32_t{-7});
  w.put(points);
  w.put(std::string("subregion 3: its map failed"));
  w.put(nested);
  ByteReader r(bytes);
  std::int32_t i = 0;
  std::vector<Vec2> p;
  std::string s;
  std::vector<std::vector<int>> n;
  r.get(i), r.get(p), r.get(s), r.get(n);
  EXPECT_TRUE(r.done());
  EXPECT_EQ(i, -7);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[1].x, 1e300);
  EXPECT_EQ(p[1].y, 3e-300);
  EXPECT_EQ(s, "subregion 3: its map failed");
  EXPECT_EQ(n, nested);
  ByteReader cut(std::string_view(bytes).substr(0, bytes.size() - 3));
  cut.get(i), cut.get(p), cut.get(s);
  EXPECT_THROW(cut.get(n), std::logic_error);
}

TEST(WorkSharing, OwnersBalanceTheCostAndDoNotDependOnAnythingButIt) {
  const std::vector<double> cost{9, 1, 1, 1, 5, 4, 3, 2, 2, 8};
  for (int processes : {1, 2, 3, 5}) {
    const std::vector<int> owner = item_owners(cost, processes);
    ASSERT_EQ(owner.size(), cost.size());
    std::vector<double> load(static_cast<std::size_t>(processes), 0.0);
    for (std::size_t i = 0; i < cost.size(); ++i) {
      ASSERT_GE(owner[i], 0);
      ASSERT_LT(owner[i], processes);
      load[static_cast<std::size_t>(owner[i])] += cost[i];
    }
    // Largest first, each to the least loaded: no process is above the mean by more than the largest item.
    const double mean = 36.0 / processes;
    for (double l : load) EXPECT_LE(l, mean + 9.0) << processes;
    EXPECT_EQ(owner, item_owners(cost, processes));
  }
  EXPECT_EQ(item_owners({3, 3, 3, 3}, 2), (std::vector<int>{0, 1, 0, 1}));
}

TEST(WorkSharing, EveryProcessEndsWithEveryItemAndTheFirstErrorInItemOrder) {
  for (int processes : {1, 2, 3}) {
    Exchange x(processes);
    const std::size_t n = 25;
    std::vector<std::vector<double>> result(static_cast<std::size_t>(processes), std::vector<double>(n, -1.0));
    std::vector<std::vector<int>> computed(static_cast<std::size_t>(processes), std::vector<int>(n, 0));
    std::vector<std::string> error(static_cast<std::size_t>(processes));
    std::vector<std::thread> threads;
    for (int rank = 0; rank < processes; ++rank)
      threads.emplace_back([&, rank] {
        const ThreadSharing sharing(x, rank);
        auto& mine = result[static_cast<std::size_t>(rank)];
        try {
          shared_for(&sharing, n, {}, "test", [&](std::size_t i) {
            computed[static_cast<std::size_t>(rank)][i] = 1;
            if (i == 17 || i == 21) throw std::runtime_error("item " + std::to_string(i) + " failed");
            mine[i] = std::sqrt(static_cast<double>(i)) + rank * 0.0;
          }, [&](std::size_t i, ByteWriter& w) { w.put(mine[i]); }, [&](std::size_t i, ByteReader& r) { r.get(mine[i]); });
        } catch (const std::exception& e) {
          error[static_cast<std::size_t>(rank)] = e.what();
        }
      });
    for (std::thread& t : threads) t.join();
    for (int rank = 0; rank < processes; ++rank) {
      EXPECT_EQ(error[static_cast<std::size_t>(rank)], "item 17 failed") << processes;
      for (std::size_t i = 0; i < n; ++i)
        if (i != 17 && i != 21) EXPECT_EQ(result[static_cast<std::size_t>(rank)][i], std::sqrt(static_cast<double>(i)));
    }
    // Each item was computed by exactly one process.
    for (std::size_t i = 0; i < n; ++i) {
      int by = 0;
      for (int rank = 0; rank < processes; ++rank) by += computed[static_cast<std::size_t>(rank)][i];
      EXPECT_EQ(by, 1) << i;
    }
  }
}
