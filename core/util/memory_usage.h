#pragma once
// The process's resident memory, from Linux's /proc (what a user's `top` shows), for the
// report's peak memory per run. Elsewhere every function answers -1 ("not measured").
namespace mcr {

// Current resident set size in MB (VmRSS).
double resident_mb();
// Peak resident set size in MB since the process started or the last reset (VmHWM).
double peak_resident_mb();
// Resets the peak to the current resident size (writes 5 to /proc/self/clear_refs, Linux 4.0+);
// false when the system does not allow it (then a peak covers the whole process).
bool reset_peak_resident();

}  // namespace mcr
