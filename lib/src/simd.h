// Which SIMD instruction set the kernels run with. Every kernel does each value's arithmetic in
// its scalar twin's order, so every choice gives the same bits; pinning one is for measuring,
// and for farms that want the same code path on every node.
#pragma once

#include <string>
#include <vector>

namespace ssgi {

// Pins the kernels to `name`: "auto" (the best this CPU and build have), a Highway target this
// build has and this CPU runs ("avx3_dl", "avx3", "avx2", "sse4", "ssse3" on x86-64, "emu128"
// or "hwy_scalar", Highway's portable ones; case does not matter), or "scalar" (the kernels'
// scalar twins, plain C++). Throws Error(kUsage) saying which
// exist. Without a call, the SSGI_SIMD environment variable decides (unset: auto).
void set_simd_target(const std::string& name);

// What the kernels run with now, as set_simd_target spells it ("avx2", "scalar").
std::string simd_target();

// The names set_simd_target accepts here, best first, lower case.
std::vector<std::string> simd_targets();

}  // namespace ssgi
