// Programs that must not link on the target (the heap guard, CMakeLists.txt): each makes one
// live allocation. heap_guard.* tests build them and expect the link to fail on __wrap_<symbol>.
#include <cstdlib>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"

namespace {

// Escapes through a volatile, so the compiler cannot elide the allocation.
void* volatile g_sink = nullptr;

}  // namespace

#if defined(HEAP_PROBE_new)
int main() {
  g_sink = new int(42);
  return 0;
}
#elif defined(HEAP_PROBE_malloc)
int main() {
  g_sink = std::malloc(64);
  return 0;
}
#elif defined(HEAP_PROBE_encode_map)
// The map encoder is in the kernel library with the decoder the target uses; it fills a
// std::vector.
harmoloc::algorithms::MapFile g_map;
int main() {
  static std::vector<std::uint8_t> bytes;
  bytes = harmoloc::algorithms::encode_map(g_map);
  g_sink = bytes.data();
  return 0;
}
#else
#error "define one HEAP_PROBE_<name>"
#endif
