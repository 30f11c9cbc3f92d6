#include "util/isa.h"

#include <atomic>
#include <cstdlib>

#include "util/error.h"

namespace mcr {

const char* isa_name(Isa level) {
  switch (level) {
    case Isa::Avx512: return "avx512";
    case Isa::Avx2: return "avx2";
    case Isa::Generic: break;
  }
  return "generic";
}

Isa best_isa() {
#ifdef MCR_X86_DISPATCH
  static const Isa best = [] {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
      return __builtin_cpu_supports("avx512f") ? Isa::Avx512 : Isa::Avx2;
    return Isa::Generic;
  }();
  return best;
#else
  return Isa::Generic;
#endif
}

Isa parse_isa(const std::string& text, const std::string& what) {
  Isa want;
  if (text == "generic") want = Isa::Generic;
  else if (text == "avx2") want = Isa::Avx2;
  else if (text == "avx512") want = Isa::Avx512;
  else throw Error(Errc::InvalidArgument, what + "='" + text + "': expected generic, avx2 or avx512");
  if (int(want) > int(best_isa()))
    throw Error(Errc::InvalidArgument, what + "='" + text + "': this CPU runs at most " + isa_name(best_isa()));
  return want;
}

namespace {

std::atomic<int>& level() {
  static std::atomic<int> v{[] {
    const char* env = std::getenv("MCRECON_ISA");
    return int(env && *env ? parse_isa(env, "MCRECON_ISA") : best_isa());
  }()};
  return v;
}

}  // namespace

Isa isa() { return Isa(level().load(std::memory_order_relaxed)); }
bool isa_at_least(Isa l) { return int(isa()) >= int(l); }

ScopedIsa::ScopedIsa(Isa l) : previous_(isa()) { level().store(int(l), std::memory_order_relaxed); }
ScopedIsa::~ScopedIsa() { level().store(int(previous_), std::memory_order_relaxed); }

}  // namespace mcr
