// What the bare-metal programs provide in place of libstdc++'s exception machinery.
//
// The kernel library holds the map decoder (used on the target) and the host-side encoder, whose
// std::vector refers to std::__throw_length_error. The linker resolves that reference from
// libstdc++ before --gc-sections drops the unused encoder, and libstdc++'s definition brings the
// whole exception runtime, including an emergency pool that calls malloc at start-up. Defined
// here, nothing of it is linked; a call would be a bug, so it traps (the fault handler reports
// it and ends the emulation with a failed status).
namespace std {

[[noreturn]] void __throw_length_error(const char*) {
  __builtin_trap();
}

}  // namespace std
