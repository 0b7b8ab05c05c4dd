/* glibc_floor.c - keeps libdqjulia.so loadable on glibc 2.34 and newer.
 *
 * libdqjulia.so carries libstdc++ and libgcc's unwinder inside (linked statically, hidden).
 * Built on Debian 12 (glibc 2.36), those archives call two functions that glibc added after
 * 2.34, which would raise the library's floor to 2.36:
 *   _dl_find_object (2.35)  libgcc's unwinder finds the unwind tables of the code an
 *                           exception passes through;
 *   arc4random      (2.36)  std::random_device's default source.
 * This file defines both for the library's own use (the version script keeps them local, so
 * nothing outside the library sees them), from functions every glibc since 2.25 has:
 * dl_iterate_phdr and getrandom. scripts/check-library.sh checks the floor of the result.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <link.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/random.h>
#include <unistd.h>

#if defined(__linux__) && defined(DLFO_STRUCT_HAS_EH_DBASE)

struct find_state {
    uintptr_t address;
    struct dl_find_object* result;
    int found;
};

/* For the loaded object whose PT_LOAD segments contain the address: its extent and the
 * address of its PT_GNU_EH_FRAME segment (the .eh_frame_hdr the unwinder searches). */
static int find_object(struct dl_phdr_info* info, size_t size, void* data) {
    (void)size;
    struct find_state* state = data;
    uintptr_t low = UINTPTR_MAX, high = 0;
    void* eh_frame = NULL;
    int contains = 0;
    for (ElfW(Half) i = 0; i < info->dlpi_phnum; ++i) {
        const ElfW(Phdr)* segment = &info->dlpi_phdr[i];
        const uintptr_t start = info->dlpi_addr + segment->p_vaddr;
        if (segment->p_type == PT_LOAD) {
            const uintptr_t end = start + segment->p_memsz;
            if (start < low) low = start;
            if (end > high) high = end;
            if (state->address >= start && state->address < end) contains = 1;
        } else if (segment->p_type == PT_GNU_EH_FRAME) {
            eh_frame = (void*)start;
        }
    }
    if (!contains) return 0;
    state->result->dlfo_flags = 0;
    state->result->dlfo_map_start = (void*)low;
    state->result->dlfo_map_end = (void*)high;
    state->result->dlfo_link_map = NULL; /* not read by the unwinder */
    state->result->dlfo_eh_frame = eh_frame;
    state->found = 1;
    return 1;
}

int _dl_find_object(void* address, struct dl_find_object* result) {
    struct find_state state = {(uintptr_t)address, result, 0};
    dl_iterate_phdr(find_object, &state);
    return state.found ? 0 : -1;
}

#endif

uint32_t arc4random(void) {
    uint32_t value;
    for (;;) {
        const ssize_t got = getrandom(&value, sizeof value, 0);
        if (got == (ssize_t)sizeof value) return value;
        if (got < 0 && errno == EINTR) continue;
        break; /* no getrandom (old kernel, seccomp): the kernel's device */
    }
    const int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        const ssize_t got = read(fd, &value, sizeof value);
        close(fd);
        if (got == (ssize_t)sizeof value) return value;
    }
    abort(); /* as glibc's arc4random does when no randomness can be had */
}
