#include "mpi_world.hpp"

// The C API only: not Open MPI's deprecated C++ bindings.
#ifndef OMPI_SKIP_MPICXX
#define OMPI_SKIP_MPICXX 1
#endif
#include <mpi.h>

#include <sched.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <thread>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"

namespace hattr::cli {
namespace {

/// Where each rank's values start in the gathered array, and their total.
std::vector<int> offsetsOf(const std::vector<int>& counts, int& total) {
  std::vector<int> offsets(counts.size());
  total = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    offsets[i] = total;
    total += counts[i];
  }
  return offsets;
}

void check(int status, const char* call) {
  if (status != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + call + " failed");
}

}  // namespace

bool MpiWorld::launched() {
  // Open MPI's mpirun sets OMPI_COMM_WORLD_SIZE; PMIx launchers (srun --mpi=pmix) PMIX_RANK.
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMIX_RANK") != nullptr;
}

MpiWorld::MpiWorld() {
  if (!launched()) return;
  // Threads may run beside MPI (a study's subjects at once); only this thread calls it.
  int provided = 0;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  initialized_ = true;
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
  // The ranks on this machine: those sharing its memory (any launcher, not only mpirun).
  MPI_Comm local = MPI_COMM_NULL;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local), "MPI_Comm_split_type");
  check(MPI_Comm_size(local, &local_size_), "MPI_Comm_size");
  MPI_Comm_free(&local);
}

MpiWorld::~MpiWorld() { finalize(); }

void MpiWorld::finalize() noexcept {
  if (initialized_) MPI_Finalize();
  initialized_ = false;
}

int MpiWorld::firstFailedRank(bool failed) const {
  if (!initialized_) return failed ? 0 : size_;
  const int mine = failed ? rank_ : size_;
  int first = size_;
  check(MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  return first;
}

std::vector<double> MpiWorld::gatherToRoot(const std::vector<double>& mine) const {
  if (!initialized_ || size_ == 1) return mine;
  // Counts first, then the values, each rank's after the one before.
  int count = static_cast<int>(mine.size());
  std::vector<int> counts(rank_ == 0 ? size_ : 0);
  check(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  int total = 0;
  const std::vector<int> offsets = offsetsOf(counts, total);
  std::vector<double> all(static_cast<std::size_t>(total));
  check(MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0,
                    MPI_COMM_WORLD),
        "MPI_Gatherv");
  return all;
}

std::vector<double> MpiWorld::gatherToAll(const std::vector<double>& mine) const {
  if (!initialized_ || size_ == 1) return mine;
  int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size_));
  check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  int total = 0;
  const std::vector<int> offsets = offsetsOf(counts, total);
  std::vector<double> all(static_cast<std::size_t>(total));
  check(MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE,
                       MPI_COMM_WORLD),
        "MPI_Allgatherv");
  return all;
}

void MpiWorld::abort(int code) const {
  if (initialized_) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

namespace {

/// The cores this process may use.
int usableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace

int threadsPerProcess(int asked, const MpiWorld& world) {
  if (asked > 0) return asked;
  const int usable = usableCores();
  const int machine = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return usable < machine ? usable : std::max(1, usable / world.localSize());
}

int exitCodeOf(const std::exception_ptr& failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError&) {
    return kBadInput;
  } catch (...) {
    return kRuntimeFailure;
  }
}

void printFailure(const std::exception_ptr& failure, const MpiWorld& world) {
  const std::string rank = world.rank() == 0 ? "" : fmt::format("rank {}: ", world.rank());
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    std::cerr << "hattr: error: " << rank << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "hattr: failed: " << rank << e.what() << "\n";
  } catch (...) {
    std::cerr << "hattr: failed: " << rank << "an unknown error\n";
  }
}

void endIfAnyRankFailed(const MpiWorld& world, const std::exception_ptr& failure) {
  if (world.size() == 1 && failure) std::rethrow_exception(failure);
  const int first_failed = world.firstFailedRank(failure != nullptr);
  if (first_failed == world.size()) return;
  if (world.rank() == first_failed) printFailure(failure, world);
  const bool failed_otherwise = failure && exitCodeOf(failure) == kRuntimeFailure;
  throw ExitQuietly{world.firstFailedRank(failed_otherwise) < world.size() ? kRuntimeFailure : kBadInput};
}

}  // namespace hattr::cli
