// Capture rigs on worker threads, so the bake's item buffers and impostor
// captures use every core (docs/decisions/0016).
//
// Each worker owns one CaptureRig for the pool's life: its own GL context,
// current on that thread only, with every block uploaded. `run` hands out
// task indices; a task writes its result where its index says, so a bake
// gives the same bytes with any number of workers (rasterisation is the same
// in every context of one driver).
#pragma once
#include <cstddef>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

#include "bake/capture.h"
#include "geo/mesh.h"

namespace blvd::bake {

class RigPool {
 public:
  // Starts `workers` threads (0: one per online CPU), each making its rig of
  // `side` x `side` pixels, with the blocks `draw` names (empty: all).
  // Throws what a rig throws (core::Error(Backend)).
  RigPool(const std::vector<geo::MeshData>& block_meshes, int side, int workers, const std::vector<bool>& draw = {});
  ~RigPool();
  RigPool(const RigPool&) = delete;
  RigPool& operator=(const RigPool&) = delete;

  int workers() const { return static_cast<int>(threads_.size()); }
  const char* backendName() const { return backend_; }

  // Runs task(rig, i) for every i in [0, n) and returns when all are done.
  // After a task throws, the rest are skipped and the first exception is
  // rethrown here.
  void run(size_t n, const std::function<void(CaptureRig&, size_t)>& task);

  // The same in batches of `batch` indices, calling after(done) on this
  // thread after each (progress, or committing the batch's results in order).
  void runInBatches(size_t n, size_t batch, const std::function<void(CaptureRig&, size_t)>& task,
                    const std::function<void(size_t done)>& after);

  // Workers for a request of `n` (0: one per online CPU, at most 16).
  static int resolveWorkers(int n);

 private:
  struct Shared;
  void work(const std::vector<geo::MeshData>& block_meshes, int side, const std::vector<bool>& draw);

  void stopAll();

  std::unique_ptr<Shared> s_;
  std::vector<std::thread> threads_;
  const char* backend_ = "";
};

}  // namespace blvd::bake
