// ThreadSanitizer's negative control (the host-tsan preset, `./run test-tsan`): two threads
// increment a plain int without synchronisation. The test passes only if ThreadSanitizer reports
// the data race, so a TSan build that does not instrument (flags lost, a preset changed) fails
// instead of passing the hand-off tests vacuously.
#include <cstdio>
#include <thread>

namespace {
int counter = 0;  // deliberately unsynchronised
}

int main() {
  std::thread other([] {
    for (int i = 0; i < 100000; ++i) ++counter;
  });
  for (int i = 0; i < 100000; ++i) ++counter;
  other.join();
  std::printf("counter %d\n", counter);
  return 0;
}
