/* fault_shim.c - an LD_PRELOAD library that makes writes into one folder fail, for the
 * fault-injection tests (hostile_input_test.cpp, outputs_test.cpp).
 *
 * It replaces glibc's write, fsync and close (and, for mode publish, rename, renameat2, link and
 * linkat), so it works whatever the program links
 * statically (OpenVDB, TBB, libpng) as long as glibc itself is a shared library. Only
 * descriptors whose file lies in DQJ_FAULT_DIR are touched (an O_TMPFILE shows up there as
 * "DIR/#123 (deleted)"); everything else passes through. Settings, from the environment:
 *   DQJ_FAULT_DIR    the folder (absolute path)
 *   DQJ_FAULT_MODE   enospc: writes fail with ENOSPC once DQJ_FAULT_AFTER bytes were written;
 *                    short:  every write there writes at most half its bytes (at least 1), and
 *                            fails with ENOSPC after DQJ_FAULT_AFTER bytes;
 *                    fsync:  fsync fails with EIO;  close: close fails with EIO;
 *                    publish: giving a file its name there fails with EIO (rename, renameat2,
 *                            link, linkat onto a name that is not hidden, i.e. does not start
 *                            with '.'), once, after DQJ_FAULT_AFTER such names were given.
 *   DQJ_FAULT_AFTER  bytes allowed before writes fail, or names given before one fails (default 0)
 *   DQJ_FAULT_NO_TMPFILE=1  open(O_TMPFILE) fails with EOPNOTSUPP, as on a file system
 *                    without it, so the writer's fallback (a hidden, locked name) is tested
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static long long written_so_far;

static int in_fault_dir(int fd) {
    const char* dir = getenv("DQJ_FAULT_DIR");
    if (!dir || !*dir) return 0;
    char link[64], target[4096];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    const ssize_t length = readlink(link, target, sizeof target - 1);
    if (length <= 0) return 0;
    target[length] = '\0';
    const size_t dirLength = strlen(dir);
    return strncmp(target, dir, dirLength) == 0 && target[dirLength] == '/';
}

static int mode_is(const char* mode) {
    const char* value = getenv("DQJ_FAULT_MODE");
    return value && strcmp(value, mode) == 0;
}

ssize_t write(int fd, const void* data, size_t size) {
    static ssize_t (*real_write)(int, const void*, size_t);
    if (!real_write) real_write = (ssize_t(*)(int, const void*, size_t))dlsym(RTLD_NEXT, "write");
    if (size > 0 && (mode_is("enospc") || mode_is("short")) && in_fault_dir(fd)) {
        const char* after = getenv("DQJ_FAULT_AFTER");
        const long long allowed = after ? atoll(after) : 0;
        if (written_so_far >= allowed) {
            errno = ENOSPC;
            return -1;
        }
        if (mode_is("short") && size > 1) size /= 2;
        if ((long long)size > allowed - written_so_far) size = (size_t)(allowed - written_so_far);
        const ssize_t done = real_write(fd, data, size);
        if (done > 0) written_so_far += done;
        return done;
    }
    return real_write(fd, data, size);
}

static int refuse_tmpfile(int flags) {
    const char* value = getenv("DQJ_FAULT_NO_TMPFILE");
    return (flags & O_TMPFILE) == O_TMPFILE && value && strcmp(value, "1") == 0;
}

#define DQJ_OPEN_WRAPPER(name)                                                     \
    int name(const char* path, int flags, ...) {                                   \
        static int (*real)(const char*, int, ...);                                 \
        if (!real) real = (int (*)(const char*, int, ...))dlsym(RTLD_NEXT, #name); \
        mode_t mode = 0;                                                           \
        if (flags & (O_CREAT | O_TMPFILE)) {                                       \
            va_list arguments;                                                     \
            va_start(arguments, flags);                                            \
            mode = va_arg(arguments, mode_t);                                      \
            va_end(arguments);                                                     \
        }                                                                          \
        if (refuse_tmpfile(flags)) {                                               \
            errno = EOPNOTSUPP;                                                    \
            return -1;                                                             \
        }                                                                          \
        return real(path, flags, mode);                                            \
    }
DQJ_OPEN_WRAPPER(open)
DQJ_OPEN_WRAPPER(open64)

int fsync(int fd) {
    static int (*real_fsync)(int);
    if (!real_fsync) real_fsync = (int (*)(int))dlsym(RTLD_NEXT, "fsync");
    if (mode_is("fsync") && in_fault_dir(fd)) {
        errno = EIO;
        return -1;
    }
    return real_fsync(fd);
}

int close(int fd) {
    static int (*real_close)(int);
    if (!real_close) real_close = (int (*)(int))dlsym(RTLD_NEXT, "close");
    if (mode_is("close") && in_fault_dir(fd)) {
        real_close(fd); /* the descriptor is gone either way, as with a real failing close */
        errno = EIO;
        return -1;
    }
    return real_close(fd);
}

/* Whether giving `path` its name is the one that fails (mode publish): a visible name in the fault
 * folder, after DQJ_FAULT_AFTER others. Only that one fails, so putting files back still works. */
static long long names_given;

static int publish_fails(const char* path) {
    const char* dir = getenv("DQJ_FAULT_DIR");
    if (!mode_is("publish") || !dir || !*dir || !path) return 0;
    const size_t dirLength = strlen(dir);
    if (strncmp(path, dir, dirLength) != 0 || path[dirLength] != '/') return 0;
    const char* name = strrchr(path, '/') + 1;
    if (name[0] == '.') return 0;
    const char* after = getenv("DQJ_FAULT_AFTER");
    return names_given++ == (after ? atoll(after) : 0);
}

int rename(const char* from, const char* to) {
    static int (*real_rename)(const char*, const char*);
    if (!real_rename) real_rename = (int (*)(const char*, const char*))dlsym(RTLD_NEXT, "rename");
    if (publish_fails(to)) {
        errno = EIO;
        return -1;
    }
    return real_rename(from, to);
}

int renameat2(int fromDir, const char* from, int toDir, const char* to, unsigned int flags) {
    static int (*real_renameat2)(int, const char*, int, const char*, unsigned int);
    if (!real_renameat2)
        real_renameat2 = (int (*)(int, const char*, int, const char*, unsigned int))dlsym(RTLD_NEXT, "renameat2");
    if (publish_fails(to)) {
        errno = EIO;
        return -1;
    }
    return real_renameat2(fromDir, from, toDir, to, flags);
}

int link(const char* from, const char* to) {
    static int (*real_link)(const char*, const char*);
    if (!real_link) real_link = (int (*)(const char*, const char*))dlsym(RTLD_NEXT, "link");
    if (publish_fails(to)) {
        errno = EIO;
        return -1;
    }
    return real_link(from, to);
}

int linkat(int fromDir, const char* from, int toDir, const char* to, int flags) {
    static int (*real_linkat)(int, const char*, int, const char*, int);
    if (!real_linkat) real_linkat = (int (*)(int, const char*, int, const char*, int))dlsym(RTLD_NEXT, "linkat");
    if (publish_fails(to)) {
        errno = EIO;
        return -1;
    }
    return real_linkat(fromDir, from, toDir, to, flags);
}
