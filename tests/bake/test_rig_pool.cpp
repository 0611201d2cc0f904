// The bake's worker pool (bake/rig_pool.h): every task index runs once, on
// workers that each hold their own rig; a failing task's exception reaches the
// caller and the pool stays usable; batches report in order.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "bake/rig_pool.h"

namespace blvd::bake {
namespace {

TEST(RigPool, EveryTaskRunsOnceOnWorkersWithTheirOwnRig) {
  RigPool pool({}, 64, 3);
  ASSERT_EQ(pool.workers(), 3);
  std::vector<std::atomic<int>> runs(500);
  std::mutex m;
  std::set<CaptureRig*> rigs;
  std::set<std::thread::id> threads;
  pool.run(runs.size(), [&](CaptureRig& rig, size_t i) {
    ++runs[i];
    std::lock_guard<std::mutex> lk(m);
    rigs.insert(&rig);
    threads.insert(std::this_thread::get_id());
  });
  for (size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(runs[i].load(), 1) << "task " << i;
  EXPECT_EQ(rigs.size(), threads.size());  // one rig per worker thread
  EXPECT_FALSE(threads.count(std::this_thread::get_id()));
}

TEST(RigPool, AFailingTaskThrowsHereAndThePoolGoesOn) {
  RigPool pool({}, 64, 2);
  EXPECT_THROW(pool.run(100, [](CaptureRig&, size_t i) {
    if (i == 7) throw std::runtime_error("task 7");
  }),
               std::runtime_error);
  std::atomic<int> n{0};
  pool.run(10, [&](CaptureRig&, size_t) { ++n; });
  EXPECT_EQ(n.load(), 10);
}

TEST(RigPool, BatchesReportInOrder) {
  RigPool pool({}, 64, 2);
  std::vector<size_t> done;
  std::atomic<int> n{0};
  pool.runInBatches(95, 10, [&](CaptureRig&, size_t) { ++n; }, [&](size_t d) { done.push_back(d); });
  EXPECT_EQ(n.load(), 95);
  ASSERT_EQ(done.size(), 10u);
  for (size_t k = 0; k < 9; ++k) EXPECT_EQ(done[k], 10 * (k + 1));
  EXPECT_EQ(done.back(), 95u);
}

}  // namespace
}  // namespace blvd::bake
