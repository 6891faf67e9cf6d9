#include "core/blas_kernels.h"

#include <cstdlib>
#include <mutex>

#if defined(QGP_STATIC_OPENBLAS)
// The extension zip's library holds Debian's static DYNAMIC_ARCH OpenBLAS.
extern "C" {
void gotoblas_dynamic_init(void);
void gotoblas_dynamic_quit(void);
char* openblas_get_corename(void);
}
#elif defined(__linux__)
#include <dlfcn.h>
#endif

namespace qgp {
namespace {

// OpenBLAS's name for its baseline x86-64 kernels (its choice for a CPU it does not know).
constexpr const char* kPinnedCore = "Prescott";

// The entry points of a DYNAMIC_ARCH OpenBLAS: `quit` forgets the kernel table, `init` picks one
// again (by OPENBLAS_CORETYPE when set). Null where this process has no such BLAS.
struct OpenBlas {
  void (*init)() = nullptr;
  void (*quit)() = nullptr;
  char* (*corename)() = nullptr;
};

OpenBlas find_openblas() {
  OpenBlas blas;
#if defined(QGP_STATIC_OPENBLAS)
  blas = {gotoblas_dynamic_init, gotoblas_dynamic_quit, openblas_get_corename};
#elif defined(__linux__)
  // The OpenBLAS this library's dependencies loaded (MUMPS links it, CHOLMOD reaches it through
  // libblas.so.3), in whatever scope it was loaded; NOLOAD never loads another one.
  if (void* lib = dlopen("libopenblas.so.0", RTLD_NOW | RTLD_NOLOAD)) {
    blas.init = reinterpret_cast<void (*)()>(dlsym(lib, "gotoblas_dynamic_init"));
    blas.quit = reinterpret_cast<void (*)()>(dlsym(lib, "gotoblas_dynamic_quit"));
    blas.corename = reinterpret_cast<char* (*)()>(dlsym(lib, "openblas_get_corename"));
    dlclose(lib);  // the dependents keep it loaded
  }
#endif
  return blas;
}

}  // namespace

void pin_blas_kernels() {
  static std::once_flag once;
  std::call_once(once, [] {
    const OpenBlas blas = find_openblas();
    if (!blas.init || !blas.quit || std::getenv("OPENBLAS_CORETYPE")) return;
#if defined(__linux__)
    setenv("OPENBLAS_CORETYPE", kPinnedCore, 0);
    blas.quit();
    blas.init();
    unsetenv("OPENBLAS_CORETYPE");
#endif
  });
}

std::string blas_kernels() {
  const OpenBlas blas = find_openblas();
  const char* name = blas.corename ? blas.corename() : nullptr;
  return name ? name : "";
}

}  // namespace qgp
