/* launcher.c - bin/dqjulia of an installed tree on Linux (the archive, the Python wheel): checks
 * that this system's glibc is at least the floor the command needs (DQJ_GLIBC_FLOOR), then runs
 * the command itself, libexec/dqjulia/dqjulia beside it, in the same process (execv) with the
 * same arguments.
 *
 * Without it, a glibc below the floor refuses the command in the dynamic loader, before main,
 * with "version `GLIBC_2.34' not found", which names neither dqjulia nor what to do. So the
 * launcher must itself run on any glibc: it needs only the oldest x86-64 symbol versions
 * (GLIBC_2.2.5, 2002). The C start files of a glibc 2.34 or newer call __libc_start_main@GLIBC_2.34;
 * the launcher is linked without them (-nostartfiles) and brings its own _start, which calls
 * the GLIBC_2.2.5 version every glibc still has. tests/cleanroom/check_library.py checks that
 * it needs nothing newer; tests/release runs it on Debian 11 (glibc 2.31).
 * Cost: one execv (well under a millisecond).
 */
#define _GNU_SOURCE
#include <errno.h>
#include <gnu/libc-version.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#if !defined(DQJ_GLIBC_FLOOR_MAJOR) || !defined(DQJ_GLIBC_FLOOR_MINOR) || !defined(DQJ_VERSION_TEXT)
#error "the build defines DQJ_GLIBC_FLOOR_MAJOR, DQJ_GLIBC_FLOOR_MINOR and DQJ_VERSION_TEXT"
#endif

/* The command, relative to the folder of the launcher (bin/). */
#define DQJ_COMMAND_FROM_BIN "/../libexec/dqjulia/dqjulia"

/* The process's entry point (x86-64 System V ABI: argc at the stack pointer, argv above it, the
 * dynamic loader's finaliser in rdx): __libc_start_main(main, argc, argv, init, fini,
 * rtld_fini, stack_end), with no init or fini (the launcher has no constructors), then main's
 * status to exit. Bound to the symbol version of glibc 2.2.5. */
__asm__(
    ".symver __libc_start_main, __libc_start_main@GLIBC_2.2.5\n"
    ".text\n"
    ".globl _start\n"
    ".type _start, @function\n"
    "_start:\n"
    "    xorl %ebp, %ebp\n"       /* the outermost frame */
    "    movq %rdx, %r9\n"        /* rtld_fini */
    "    popq %rsi\n"             /* argc */
    "    movq %rsp, %rdx\n"       /* argv */
    "    andq $-16, %rsp\n"       /* the ABI's 16-byte alignment at a call */
    "    pushq %rax\n"            /* (padding, keeps that alignment) */
    "    pushq %rsp\n"            /* stack_end, the 7th argument */
    "    xorl %r8d, %r8d\n"       /* fini */
    "    xorl %ecx, %ecx\n"       /* init */
    "    leaq main(%rip), %rdi\n" /* main */
    "    call *__libc_start_main@GOTPCREL(%rip)\n"
    "    hlt\n"
    ".size _start, . - _start\n");

/* "2.31" -> 2 and 31; 0 if the text does not start with MAJOR.MINOR. */
static int parse_version(const char* text, int* major, int* minor) {
    int* parts[2] = {major, minor};
    for (int i = 0; i < 2; ++i) {
        if (*text < '0' || *text > '9') return 0;
        *parts[i] = 0;
        while (*text >= '0' && *text <= '9') *parts[i] = *parts[i] * 10 + (*text++ - '0');
        if (i == 0 && *text++ != '.') return 0;
    }
    return 1;
}

int main(int argc, char** argv) {
    (void)argc;
    const char* glibc = gnu_get_libc_version();
    int major = 0, minor = 0;
    if (!parse_version(glibc, &major, &minor) || major < DQJ_GLIBC_FLOOR_MAJOR ||
        (major == DQJ_GLIBC_FLOOR_MAJOR && minor < DQJ_GLIBC_FLOOR_MINOR)) {
        fprintf(stderr,
                "dqjulia: this system has glibc %s, but dqjulia %s needs glibc %d.%d or newer (Debian 12, "
                "Ubuntu 22.04, RHEL 9, Fedora 35 and later). Use a newer system, or build dqjulia from source "
                "on this one.\n",
                glibc, DQJ_VERSION_TEXT, DQJ_GLIBC_FLOOR_MAJOR, DQJ_GLIBC_FLOOR_MINOR);
        return 1;
    }
    /* The command beside the launcher's own file (symbolic links to it resolved). */
    char path[PATH_MAX];
    const ssize_t length = readlink("/proc/self/exe", path, sizeof path);
    const size_t suffix = sizeof DQJ_COMMAND_FROM_BIN;
    if (length <= 0 || (size_t)length >= sizeof path) {
        fprintf(stderr, "dqjulia: cannot find the launcher's own path (/proc/self/exe): %s\n",
                length < 0 ? strerror(errno) : "too long");
        return 1;
    }
    path[length] = '\0';
    char* slash = strrchr(path, '/');
    if (slash == NULL || (size_t)(slash - path) + suffix > sizeof path) {
        fprintf(stderr, "dqjulia: the launcher's path is too long: %s\n", path);
        return 1;
    }
    memcpy(slash, DQJ_COMMAND_FROM_BIN, suffix);
    execv(path, argv);
    fprintf(stderr, "dqjulia: cannot run %s (an incomplete installation?): %s\n", path, strerror(errno));
    return 1;
}
