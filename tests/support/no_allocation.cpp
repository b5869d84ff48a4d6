#include "support/no_allocation.hpp"

#include <dlfcn.h>
#include <pthread.h>

#include <cstdlib>
#include <new>

namespace {

thread_local bool tl_guard = false;
thread_local std::uint64_t tl_allocations = 0;
thread_local std::uint64_t tl_locks = 0;

void* allocate(std::size_t size) {
  if (tl_guard) ++tl_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

#if !defined(__SANITIZE_THREAD__)
// Interposes the C library's mutex lock (std::mutex and friends end up here).
extern "C" int pthread_mutex_lock(pthread_mutex_t* mutex) {
  using Lock = int (*)(pthread_mutex_t*);
  static const auto real = reinterpret_cast<Lock>(::dlsym(RTLD_NEXT, "pthread_mutex_lock"));
  if (tl_guard) ++tl_locks;
  return real(mutex);
}
#endif

namespace hattr::test {

NoAllocationScope::NoAllocationScope() {
  tl_allocations = 0;
  tl_locks = 0;
  tl_guard = true;
}

NoAllocationScope::~NoAllocationScope() { tl_guard = false; }

std::uint64_t NoAllocationScope::allocations() const { return tl_allocations; }
std::uint64_t NoAllocationScope::locks() const { return tl_locks; }

bool lockHookActive() {
#if defined(__SANITIZE_THREAD__)
  return false;
#else
  return true;
#endif
}

}  // namespace hattr::test
