// ThreadSanitizer's negative control (the host-tsan preset, `./run test-tsan`): two threads
// write a plain int without synchronisation. The test passes only if ThreadSanitizer reports the
// data race, so a TSan build that does not instrument (flags lost, a preset changed) fails
// instead of passing the hand-off tests vacuously.
//
// The race must be reported on every run, however loaded the machine: a version that let two
// loops of 100,000 increments run freely once reported nothing on a busy CI machine (issue 16:
// one thread may run to its end before the other starts, or its accesses may lie outside what
// TSan still remembers). Here the two threads take turns, round after round, handing the turn
// over through a relaxed atomic: each write happens right after the other thread's, so TSan
// always has the other write in view, and relaxed operations create no happens-before between
// the threads (TSan's model, as C++'s), so every such pair is a race it must report.
#include <atomic>
#include <cstdio>
#include <thread>

namespace {

int counter = 0;           // deliberately unsynchronised
std::atomic<int> turn{0};  // the round whose write is next; even rounds are main's
constexpr int kRounds = 64;

// Waits (relaxed, so no happens-before) for round @p round, writes, hands the turn over.
void take_turns(int parity) {
  for (int round = parity; round < 2 * kRounds; round += 2) {
    while (turn.load(std::memory_order_relaxed) != round) {
    }
    ++counter;  // the race: the other thread wrote it just before, with nothing ordering the two
    turn.store(round + 1, std::memory_order_relaxed);
  }
}

}  // namespace

int main() {
  std::thread other(take_turns, 1);
  take_turns(0);
  other.join();
  std::printf("counter %d after %d rounds\n", counter, 2 * kRounds);
  return 0;
}
