#include "simd.h"

#include <OpenImageIO/strutil.h>
#include <hwy/targets.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <mutex>

#include "gi/denoise_kernels.h"
#include "log.h"
#include "throw.h"

namespace ssgi {
namespace {

// A Highway target as --simd spells it: "avx2"; Highway's own one-lane target is "hwy_scalar",
// apart from "scalar", the kernels' scalar twins.
std::string target_name(std::int64_t target) {
  const std::string name = OIIO::Strutil::lower(hwy::TargetName(target));
  return name == "scalar" ? "hwy_scalar" : name;
}

// The Highway targets this build compiled and this CPU runs, best first (before any pin).
const std::vector<std::int64_t>& available_targets() {
  static const std::vector<std::int64_t> targets = [] {
    std::vector<std::int64_t> t = hwy::SupportedAndGeneratedTargets();
    std::sort(t.begin(), t.end());  // lower bits are the better targets
    return t;
  }();
  return targets;
}

std::atomic<bool> g_scalar{false};
std::once_flag g_from_environment;

void apply(const std::string& name) {
  const std::string wanted = OIIO::Strutil::lower(name);
  if (wanted == "auto") {
    hwy::SetSupportedTargetsForTest(0);
    g_scalar = false;
  } else if (wanted == "scalar") {
    hwy::SetSupportedTargetsForTest(0);
    g_scalar = true;
  } else {
    const auto& targets = available_targets();
    const auto it = std::find_if(targets.begin(), targets.end(),
                                 [&](std::int64_t t) { return target_name(t) == wanted; });
    if (it == targets.end()) {
      std::string known;
      for (const std::string& n : simd_targets()) known += (known.empty() ? "" : ", ") + n;
      throw_usage("SIMD target '" + name + "' is not one this CPU and build have (" + known + ")");
    }
    hwy::SetSupportedTargetsForTest(*it);
    g_scalar = false;
  }
  // Dispatch tables choose again at their next call.
  hwy::GetChosenTarget().Update(hwy::SupportedTargets());
}

// SSGI_SIMD, once: a name that is not a target here is warned about and ignored, never thrown
// from a kernel's thread (ssgi's programs check it first, as a usage error).
void from_environment() {
  std::call_once(g_from_environment, [] {
    const char* v = std::getenv("SSGI_SIMD");
    if (v == nullptr || *v == '\0') return;
    try {
      apply(v);
    } catch (const Error& e) {
      log_warning(std::string("SSGI_SIMD: ") + e.what() + "; using auto");
    }
  });
}

}  // namespace

void set_simd_target(const std::string& name) {
  from_environment();
  apply(name);
}

std::string simd_target() {
  from_environment();
  if (g_scalar) return "scalar";
  const std::int64_t supported = hwy::SupportedTargets() & HWY_TARGETS;
  return supported ? target_name(supported & -supported) : "scalar";
}

std::vector<std::string> simd_targets() {
  std::vector<std::string> names{"auto"};
  for (std::int64_t t : available_targets()) names.push_back(target_name(t));
  names.push_back("scalar");
  return names;
}

namespace detail {

bool simd_forced_scalar() {
  from_environment();
  return g_scalar.load(std::memory_order_relaxed);
}

}  // namespace detail
}  // namespace ssgi
