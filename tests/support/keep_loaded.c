/*
 * AddressSanitizer builds only (-DANVIL_SANITIZE=ON): a dlclose that leaves the library
 * loaded, linked into the program and the tests so that it takes the place of libc's for
 * every library.  Mesa unloads its driver in eglTerminate; what the driver still holds in its
 * globals then looks leaked to LeakSanitizer, from an "unknown module" with no stack to
 * suppress.  Kept loaded, the driver's memory stays reachable, its code stays named, and
 * LeakSanitizer reports only what nothing holds (tests/asan.supp names the libraries' own).
 */
#include <dlfcn.h>

int dlclose(void *handle)
{
    (void)handle;
    return 0;
}
