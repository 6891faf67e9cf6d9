/* _gfortran_os_error_at for the portable build (cmake/portable_dependencies.cmake).
 *
 * Debian's MUMPS is compiled by gfortran 12, whose code calls _gfortran_os_error_at (GCC 10 and
 * later) when an ALLOCATE without STAT= fails. The bundled manylinux libgfortran is GCC 8's ABI
 * (manylinux toolchains link newer runtime entry points statically from a "nonshared" archive), so
 * the entry point is provided here. As in GCC's libgfortran (runtime/error.c), the message is
 * "WHERE: MESSAGE" and the run ends through the runtime's own os_error, which adds errno's text. */
#include <stdarg.h>
#include <stdio.h>

void _gfortran_os_error(const char* message) __attribute__((noreturn));

__attribute__((noreturn)) void _gfortran_os_error_at(const char* where, const char* message, ...) {
  char text[512];
  int length = snprintf(text, sizeof text, "%s: ", where);
  if (length < 0 || (size_t)length >= sizeof text) length = 0;
  va_list arguments;
  va_start(arguments, message);
  vsnprintf(text + length, sizeof text - (size_t)length, message, arguments);
  va_end(arguments);
  _gfortran_os_error(text);
}
