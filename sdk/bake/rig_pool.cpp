// Worker threads with a capture rig each; the contract is in rig_pool.h.
#include "bake/rig_pool.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>

namespace blvd::bake {

struct RigPool::Shared {
  std::mutex m;
  std::condition_variable work_cv, done_cv;
  // Start-up: rigs made (or failed), the first failure, the backend's name.
  int ready = 0;
  std::exception_ptr start_error;
  const char* backend = nullptr;
  // The current batch: a new generation wakes the workers.
  uint64_t generation = 0;
  bool stop = false;
  size_t n = 0;
  const std::function<void(CaptureRig&, size_t)>* task = nullptr;
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  size_t active = 0;  // workers not yet done with the batch
};

int RigPool::resolveWorkers(int n) {
  if (n > 0) return n;
  return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 16u));
}

RigPool::RigPool(const std::vector<geo::MeshData>& block_meshes, int side, int workers, const std::vector<bool>& draw)
    : s_(new Shared) {
  const int n = resolveWorkers(workers);
  for (int i = 0; i < n; ++i) threads_.emplace_back([this, &block_meshes, side, &draw] { work(block_meshes, side, draw); });
  std::exception_ptr failed;
  {
    std::unique_lock<std::mutex> lk(s_->m);
    s_->done_cv.wait(lk, [&] { return s_->ready == n; });
    failed = s_->start_error;
    backend_ = s_->backend ? s_->backend : "";
  }
  if (failed) {
    stopAll();
    std::rethrow_exception(failed);
  }
}

RigPool::~RigPool() { stopAll(); }

void RigPool::stopAll() {
  {
    std::lock_guard<std::mutex> lk(s_->m);
    s_->stop = true;
  }
  s_->work_cv.notify_all();
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
}

void RigPool::work(const std::vector<geo::MeshData>& block_meshes, int side, const std::vector<bool>& draw) {
  Shared& s = *s_;
  std::unique_ptr<CaptureRig> rig;
  try {
    rig = std::make_unique<CaptureRig>(block_meshes, side, side, render::Backend::Auto, draw);
  } catch (...) {
    std::lock_guard<std::mutex> lk(s.m);
    if (!s.start_error) s.start_error = std::current_exception();
  }
  {
    std::lock_guard<std::mutex> lk(s.m);
    if (rig && !s.backend) s.backend = rig->backendName();
    ++s.ready;
  }
  s.done_cv.notify_all();
  if (!rig) return;
  uint64_t seen = 0;
  for (;;) {
    const std::function<void(CaptureRig&, size_t)>* task = nullptr;
    size_t n = 0;
    {
      std::unique_lock<std::mutex> lk(s.m);
      s.work_cv.wait(lk, [&] { return s.stop || s.generation != seen; });
      if (s.stop) return;
      seen = s.generation;
      task = s.task;
      n = s.n;
    }
    for (size_t i; !s.failed.load() && (i = s.next.fetch_add(1)) < n;) {
      try {
        (*task)(*rig, i);
      } catch (...) {
        std::lock_guard<std::mutex> lk(s.m);
        if (!s.error) s.error = std::current_exception();
        s.failed = true;
      }
    }
    std::lock_guard<std::mutex> lk(s.m);
    if (--s.active == 0) s.done_cv.notify_all();
  }
}

void RigPool::run(size_t n, const std::function<void(CaptureRig&, size_t)>& task) {
  if (n == 0) return;
  Shared& s = *s_;
  {
    std::lock_guard<std::mutex> lk(s.m);
    s.task = &task;
    s.n = n;
    s.next = 0;
    s.failed = false;
    s.error = nullptr;
    s.active = threads_.size();
    ++s.generation;
  }
  s.work_cv.notify_all();
  std::exception_ptr error;
  {
    std::unique_lock<std::mutex> lk(s.m);
    s.done_cv.wait(lk, [&] { return s.active == 0; });
    error = s.error;
  }
  if (error) std::rethrow_exception(error);
}

void RigPool::runInBatches(size_t n, size_t batch, const std::function<void(CaptureRig&, size_t)>& task,
                           const std::function<void(size_t done)>& after) {
  batch = std::max<size_t>(1, batch);
  for (size_t b0 = 0; b0 < n; b0 += batch) {
    const size_t m = std::min(batch, n - b0);
    run(m, [&](CaptureRig& rig, size_t i) { task(rig, b0 + i); });
    if (after) after(b0 + m);
  }
}

}  // namespace blvd::bake
