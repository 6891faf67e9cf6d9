// The same BLAS arithmetic on every x86-64 machine, so that the same input and options give the same
// output on every machine, not only on every run of one.
//
// CHOLMOD's supernodal factorizations and MUMPS's (under Ipopt) run their dense fronts through BLAS.
// OpenBLAS built with DYNAMIC_ARCH (Debian's packages, and the static archive in the extension zip)
// picks its kernels by the CPU at load time: Haswell, SkylakeX and Cooperlake kernels round
// differently, and the pipeline's outputs then differ in their last bits and, through the seamless
// map, in their quads (nefertiti, mnf07 and beetle at 500 quads: other files under Cooperlake than
// under Prescott kernels on one machine; the tests' per-mesh figures held under one and not the
// other). Pinning them to OpenBLAS's baseline x86-64 kernels (Prescott: SSE3, on every x86-64 CPU
// Blender runs on) cost no time on the repair's small fronts (armadillo, nefertiti, mnf07, beetle:
// within 5 %, 2026-12-01).
#pragma once
#include <string>

namespace qgp {

// Switches a DYNAMIC_ARCH OpenBLAS in this process to its Prescott kernels, once, before this
// library's first BLAS call (every factorization calls it first); a no-op when the user set
// OPENBLAS_CORETYPE (their choice stands) or the BLAS is another one (the Windows build's reference
// BLAS is the same on every machine already). Thread-safe; no BLAS call of this library runs while
// it switches.
void pin_blas_kernels();

// The kernels in use: OpenBLAS's core name, or "" for another BLAS.
std::string blas_kernels();

}  // namespace qgp
