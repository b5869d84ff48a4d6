#pragma once
// MPI for commands that split their work across processes (`mpirun -n N hattr sim power`):
// Open MPI from Debian, through its C API. A process that a launcher did not start is a
// world of one and never initializes MPI, so the CLI runs the same without mpirun.

#include <exception>
#include <vector>

namespace hattr::cli {

class MpiWorld {
 public:
  /// Initializes MPI when this process was started by an MPI launcher (mpirun, mpiexec, or
  /// srun with PMIx); otherwise a world of one.
  MpiWorld();
  /// Finalizes MPI (every rank must get here, or abort()).
  ~MpiWorld();
  /// Finalizes now (before exiting without unwinding); the destructor then does nothing.
  void finalize() noexcept;
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;

  [[nodiscard]] int rank() const noexcept { return rank_; }
  [[nodiscard]] int size() const noexcept { return size_; }
  /// Processes of this world on this machine (to share its cores).
  [[nodiscard]] int localSize() const noexcept { return local_size_; }
  /// The lowest rank for which `failed` is true, or size() when none is (every rank calls it).
  [[nodiscard]] int firstFailedRank(bool failed) const;
  /// Every rank's values, in rank order, on rank 0 (empty on the others).
  [[nodiscard]] std::vector<double> gatherToRoot(const std::vector<double>& mine) const;
  /// Every rank's values, in rank order, on every rank.
  [[nodiscard]] std::vector<double> gatherToAll(const std::vector<double>& mine) const;
  /// Ends every rank of the world with `code` (a rank that failed alone would leave the
  /// others waiting in a gather).
  [[noreturn]] void abort(int code) const;

  /// Whether an MPI launcher started this process (its environment says so).
  [[nodiscard]] static bool launched();

 private:
  bool initialized_ = false;
  int rank_ = 0;
  int size_ = 1;
  int local_size_ = 1;
};

/// Threads per process: as asked, else the usable cores (a launcher that binds its ranks
/// gives each fewer than the machine has) shared by this machine's ranks.
[[nodiscard]] int threadsPerProcess(int asked, const MpiWorld& world);
/// The exit code for a failure: 2 for bad input, 1 otherwise.
[[nodiscard]] int exitCodeOf(const std::exception_ptr& failure);
/// Prints a failure as main() does, naming the rank when it is not the first.
void printFailure(const std::exception_ptr& failure, const MpiWorld& world);
/// After a set-up every rank ran (`failure`: this rank's, or none): a world of one rethrows it;
/// otherwise, when any rank failed, the first that failed says why and every rank ends with the
/// same code (ExitQuietly): bad input (2) unless a rank failed otherwise (1). None is left waiting.
void endIfAnyRankFailed(const MpiWorld& world, const std::exception_ptr& failure);

}  // namespace hattr::cli
