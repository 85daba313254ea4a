// Internal: what the binding's files share. Numpy arrays in (viewed in place where their layout
// allows) and out (the C++ buffers handed over, not copied); the library's work on its own thread
// with the GIL released, and Ctrl-C turned into a cancel request and a KeyboardInterrupt.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::binding {

namespace py = pybind11;

// A computation on its own thread: its cancel flag and whether it has finished.
struct Job {
  std::atomic<bool> cancel{false};
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  // Waits up to `timeout` for the job to finish; true if it has.
  bool wait(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex);
    return finished.wait_for(lock, timeout, [&] { return done; });
  }
};

// Progress events from the library's threads, handed to a Python callable on the calling thread
// (which holds the GIL) each time run_interruptible polls: (stage, done, total); total 0 for a
// stage's start message. Only the latest fraction of each stage is kept between polls.
struct ProgressQueue {
  std::mutex mutex;
  std::vector<std::tuple<std::string, long, long>> events;
  void push(const std::string& stage, long done, long total);
  // Calls `callback` for each event since the last call (GIL held by the caller).
  void deliver(const py::object& callback);
};

// Jobs left running after a Ctrl-C, with the Python objects whose memory they still read. Those
// are released (GIL held) once the job has finished; never destroyed at exit without the GIL.
std::vector<std::pair<std::shared_ptr<Job>, py::object>>& abandoned_jobs();
void release_finished_jobs();
// At exit, jobs still running are asked to stop and waited for.
void stop_abandoned_jobs();

// Runs work(cancel) on a worker thread with the GIL released, polling for Ctrl-C every 50 ms.
// work must own everything it reads (it may outlive this call); `keep_alive` holds the Python
// objects whose memory it reads. On Ctrl-C the cancel flag is set (the library stops at its next
// stage, brick or solver iteration) and KeyboardInterrupt is raised at once: a worker that has
// not stopped within 0.2 s finishes in the background, its objects kept until then.
template <class Work>
auto run_interruptible(Work work, py::object keep_alive = py::none(),
                       const std::function<void()>& on_poll = {}) {
  using Result = decltype(work(std::declval<std::atomic<bool>&>()));
  release_finished_jobs();
  auto job = std::make_shared<Job>();
  auto result = std::make_shared<std::optional<Result>>();
  auto error = std::make_shared<std::exception_ptr>();
  std::thread([job, result, error, work = std::move(work)]() mutable {
    try {
      result->emplace(work(job->cancel));
    } catch (...) {
      *error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(job->mutex);
    job->done = true;
    job->finished.notify_all();
  }).detach();
  for (;;) {
    bool finished = false;
    {
      py::gil_scoped_release release;
      finished = job->wait(std::chrono::milliseconds(50));
    }
    if (on_poll) on_poll();  // with the GIL: the caller's Python progress callback
    if (finished) break;
    if (PyErr_CheckSignals() != 0) {
      py::error_already_set interrupt;  // the KeyboardInterrupt (or the handler's error)
      job->cancel = true;
      bool stopped = false;
      {
        py::gil_scoped_release release;
        stopped = job->wait(std::chrono::milliseconds(200));
      }
      if (!stopped) abandoned_jobs().push_back({job, std::move(keep_alive)});
      throw interrupt;
    }
  }
  if (*error) std::rethrow_exception(*error);
  return std::move(**result);
}

// A C++ matrix handed to numpy without a copy: numpy's array owns the moved matrix.
template <class Matrix>
py::array to_numpy(Matrix&& m) {
  using Scalar = typename std::decay_t<Matrix>::Scalar;
  auto* owned = new std::decay_t<Matrix>(std::forward<Matrix>(m));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::decay_t<Matrix>*>(p); });
  const py::ssize_t rows = owned->rows(), cols = owned->cols();
  return py::array_t<Scalar>({rows, cols},
                             {cols * py::ssize_t(sizeof(Scalar)), py::ssize_t(sizeof(Scalar))},
                             owned->data(), owner);
}

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The module's Python side has checked dtypes and shapes already; these checks stand guard for a
// direct call (a failed conversion is a null array, never dereferenced).
PointMatrix points_from(const DoubleArray& a, const char* what);
Mesh mesh_from(const py::array& V, const py::array& F);

// options[key] as a T, or `fallback` where the dict has no such key.
template <class T>
T get(const py::dict& options, const char* key, T fallback) {
  return options.contains(key) ? options[key].cast<T>() : fallback;
}

// The library's options from the module's option dict (sdfcontour/__init__.py's keywords).
PoissonOptions poisson_options(const py::dict& o);
ContourOptions contour_options(const py::dict& o);

Bounds bounds_of(const std::array<double, 3>& lo, const std::array<double, 3>& hi);

// The input as the library takes it: a 3D array is a grid over [lo, hi] viewed in place when it
// is C-contiguous float32 or float64 (else converted once); an (n, 4) array holds scattered
// samples. `keep` holds any converted copy.
SdfInput sdf_input(const py::array& array, const Bounds& bounds, double spacing, py::object& keep);

// A view of `block`, the samples [first, first + block.shape) of a grid of `dims` over [lo, hi]
// (`keep` holds a converted copy while the view is used).
GridView block_view(const py::array& block, const std::array<int, 3>& first,
                    const std::array<int, 3>& dims, const std::array<double, 3>& lo,
                    const std::array<double, 3>& hi, py::object& keep);

// A grid's samples along its longest axis (what the automatic choices read).
double largest(const std::array<int, 3>& dims);

// What the module's stats say of a mesh's topology, and of what adaptivity did.
py::dict topology_stats(const Mesh& mesh);
py::dict adaptivity_stats(const AdaptivityStats& s);

// The module's functions, by file: contouring (_sdfcontour.cpp), the bricks that Dask runs and
// joins (bricks.cpp), meshes and points (meshes.cpp).
void bind_bricks(py::module_& m);
void bind_meshes(py::module_& m);

}  // namespace sdfcontour::binding
