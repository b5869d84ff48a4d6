#pragma once
// Proves the servo rules in tests: inside a NoAllocationScope every operator new, and every
// pthread mutex lock, on this thread fails the test (Drake's LimitMalloc, Pinocchio's
// malloc guard). The hooks live in no_allocation.cpp and are linked only into the test
// programs that use them.

#include <cstdint>

namespace hattr::test {

class NoAllocationScope {
 public:
  NoAllocationScope();
  ~NoAllocationScope();
  NoAllocationScope(const NoAllocationScope&) = delete;
  NoAllocationScope& operator=(const NoAllocationScope&) = delete;
  /// Allocations and locks seen in the scope so far.
  [[nodiscard]] std::uint64_t allocations() const;
  [[nodiscard]] std::uint64_t locks() const;
};

/// True if the lock hook can see locks in this build (not under the thread sanitizer,
/// which intercepts the same functions).
bool lockHookActive();

}  // namespace hattr::test
