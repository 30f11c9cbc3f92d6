#pragma once
// Run-time CPU check for the hand-vectorised AVX2 paths (built only by x86-64 GCC; false
// elsewhere, where the scalar code runs).
namespace mcr {

inline bool cpu_has_avx2() {
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
  static const bool yes = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2");
  }();
  return yes;
#else
  return false;
#endif
}

}  // namespace mcr
