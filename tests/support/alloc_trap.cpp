#include "tests/support/alloc_trap.h"

#include <Eigen/Core>
#include <cstdlib>
#include <new>


namespace {
thread_local std::size_t t_count = 0;
thread_local int t_armed = 0;
thread_local std::size_t t_first_size = 0;

void note(std::size_t n) {
  ++t_count;
  if (t_armed > 0 && t_first_size == 0) t_first_size = n == 0 ? 1 : n;
}
}  // namespace

#ifdef KUAVO_SANITIZE
// AddressSanitizer owns malloc and operator new: replacing them with glibc's handed glibc blocks
// to ASan's free and back ("free(): invalid size", SIGABRT in kuavo_fw_sim). Its allocation hook
// counts every allocation of the calling thread instead, the same count the replacements keep.
// (Declared here: Debian's GCC 12 ships libasan without <sanitizer/allocator_interface.h>.)
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                          void (*free_hook)(const volatile void*));
namespace {
void on_malloc(const volatile void*, std::size_t n) { note(n); }
void on_free(const volatile void*) {}
[[maybe_unused]] const int g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(on_malloc, on_free);
}  // namespace
#else
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
}

extern "C" {
void* malloc(std::size_t n) {
  note(n);
  return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) {
  note(a * b);
  return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) {
  note(n);
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
}

void* operator new(std::size_t n) {
  void* p = malloc(n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return malloc(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return malloc(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  note(n);
  void* p = __libc_memalign(static_cast<std::size_t>(a), n);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { free(p); }
void operator delete[](void* p) noexcept { free(p); }
void operator delete(void* p, std::size_t) noexcept { free(p); }
void operator delete[](void* p, std::size_t) noexcept { free(p); }
void operator delete(void* p, std::align_val_t) noexcept { free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { free(p); }
#endif  // KUAVO_SANITIZE

namespace kuavo::test {

AllocTrap::AllocTrap()
    : start_count_(t_count), eigen_was_allowed_(Eigen::internal::is_malloc_allowed()) {
  ++t_armed;
  t_first_size = 0;
  Eigen::internal::set_is_malloc_allowed(false);
}

AllocTrap::~AllocTrap() {
  --t_armed;
  Eigen::internal::set_is_malloc_allowed(eigen_was_allowed_);
}

std::size_t AllocTrap::count() const { return t_count - start_count_; }
std::size_t AllocTrap::first_size_bytes() const { return t_first_size; }

std::size_t thread_allocation_count() { return t_count; }

}  // namespace kuavo::test
