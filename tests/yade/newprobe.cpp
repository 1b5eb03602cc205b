// ABI probe (tests/yade/abi_sizes.py): LD_PRELOAD'ed into a yade run, it replaces operator new and,
// while armed, records the size of every allocation. YADE's Python constructors allocate a class with
// `new T`, so the first size recorded after arming is sizeof(T) as Debian's libyade was compiled.
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {
constexpr int kMax = 64;
volatile int g_armed = 0;
std::size_t  g_sizes[kMax];
int          g_count = 0;
}  // namespace

extern "C" {
void woven_probe_arm() { g_count = 0, g_armed = 1; }
void woven_probe_disarm() { g_armed = 0; }
int woven_probe_count() { return g_count; }
long woven_probe_size(int k) { return k >= 0 && k < g_count ? static_cast<long>(g_sizes[k]) : -1; }
}

void* operator new(std::size_t n) {
  if (g_armed && g_count < kMax) g_sizes[g_count++] = n;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
