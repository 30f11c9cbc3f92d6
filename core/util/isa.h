#pragma once
// The one run-time instruction-set choice of every hand-vectorised path. Default: the
// best the CPU has; the environment variable MCRECON_ISA=generic|avx2|avx512 lowers it
// (read once, at the first call; a name the CPU cannot run, or an unknown one, is an
// Errc::InvalidArgument naming what was typed). Tests and benchmarks switch it with
// ScopedIsa. Every SIMD path has a generic twin; tests run both (isa_paths_test.cpp).
//
// Levels are ordered: a path written for AVX2 runs when isa() >= Isa::Avx2.
//   generic  the compiler's baseline (SSE2 on x86-64)
//   avx2     AVX2 + FMA (the paths that contract a*b+c say so; the others give the
//            generic path's bits)
//   avx512   AVX-512F (only the cross-bilateral kernel and the auto-vectorised loops
//            have such builds; other paths run their AVX2 build)
#include <string>

namespace mcr {

enum class Isa { Generic = 0, Avx2 = 1, Avx512 = 2 };

const char* isa_name(Isa isa);  // "generic", "avx2", "avx512"
Isa best_isa();                 // what this CPU can run
Isa isa();                      // the level in use
bool isa_at_least(Isa level);   // isa() >= level

// Parses "generic" / "avx2" / "avx512"; throws InvalidArgument naming `what` and the text,
// or when the CPU lacks that level.
Isa parse_isa(const std::string& text, const std::string& what);

// Sets the level for its lifetime (tests, benchmarks); not thread-safe against running filters.
class ScopedIsa {
 public:
  explicit ScopedIsa(Isa level);
  ~ScopedIsa();
  ScopedIsa(const ScopedIsa&) = delete;
  ScopedIsa& operator=(const ScopedIsa&) = delete;

 private:
  Isa previous_;
};

}  // namespace mcr

// Function attributes for the builds of one source at several levels (GCC on x86-64;
// elsewhere every level compiles to the generic code).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MCR_X86_DISPATCH 1
#define MCR_TARGET_AVX2 __attribute__((target("avx2")))
#define MCR_TARGET_AVX512 __attribute__((target("avx512f")))
#else
#define MCR_TARGET_AVX2
#define MCR_TARGET_AVX512
#endif

// `name params` calling the build of `name##_body` (an always-inline function of the
// same parameters) for the level in use: one source, auto-vectorised per level. The
// _body must not contract a*b+c (the default here: ISO C++ mode has fp-contract off),
// so every build gives the same bits.
#define MCR_ISA_BUILD(ret, name, suffix, target, params, args) \
  target ret name##suffix params { return name##_body args; }
#define MCR_ISA_VERSIONS(ret, name, params, args)                             \
  MCR_ISA_BUILD(ret, name, _avx512, MCR_TARGET_AVX512, params, args)           \
  MCR_ISA_BUILD(ret, name, _avx2, MCR_TARGET_AVX2, params, args)               \
  MCR_ISA_BUILD(ret, name, _generic, , params, args)                           \
  ret name params {                                                           \
    switch (::mcr::isa()) {                                                   \
      case ::mcr::Isa::Avx512: return name##_avx512 args;                     \
      case ::mcr::Isa::Avx2: return name##_avx2 args;                         \
      case ::mcr::Isa::Generic: break;                                        \
    }                                                                         \
    return name##_generic args;                                               \
  }
// The same with an AVX2 build only (AVX-512 runs it).
#define MCR_ISA_VERSIONS_AVX2(ret, name, params, args)                        \
  MCR_ISA_BUILD(ret, name, _avx2, MCR_TARGET_AVX2, params, args)               \
  MCR_ISA_BUILD(ret, name, _generic, , params, args)                           \
  ret name params { return ::mcr::isa_at_least(::mcr::Isa::Avx2) ? name##_avx2 args : name##_generic args; }
#define MCR_ALWAYS_INLINE inline __attribute__((always_inline))
