// platform.hpp - the one place where the toolkit meets the operating system: file names in UTF-8,
// descriptors, the steps of publishing a file atomically, memory limits and use, the processors a
// process may use, console interrupts, the program's own path and running a command.
//
// Internal to libdqjulia and the command. Code: platform_posix.cpp (Linux and other POSIX systems)
// or platform_windows.cpp (Windows, with MinGW-w64): core/CMakeLists.txt compiles one of them; what
// is the same on both, built on their steps, in platform.cpp (hidden names, readUpTo, runCommand). Every
// `#ifdef _WIN32` of core/ lives under platform/, but where a comment (`// why:`) says why it cannot
// (scripts/check-layout.py checks it). What the callers decide is the same on every system; how a
// step is done is here. Costs nothing on Linux beyond the system calls; a UTF-16 conversion per
// name on Windows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dqj::platform {

/// Whether this build runs on Windows: for the few rules that are Windows' own but written
/// portably (windowsNameProblem), so that every build compiles and tests them.
#ifdef _WIN32
inline constexpr bool kWindows = true;
#else
inline constexpr bool kWindows = false;
#endif

// --- File names: UTF-8 everywhere in the toolkit (the C ABI, the parameter file, the command's
// arguments; Blender hands UTF-8 on every platform). On Linux a name is bytes and nothing changes.
// On Windows, std::filesystem::path's char constructor reads the ANSI code page and the CRT's narrow
// fopen/open do too, so a path is made from char8_t and files are opened by their UTF-16 name.

/// A UTF-8 file name as a path. On Windows, a name that is not valid UTF-8 throws
/// std::filesystem::filesystem_error; on Linux any bytes are a name.
inline std::filesystem::path pathFromUtf8(const std::string& name) {
    return std::filesystem::path(std::u8string(name.begin(), name.end()));
}

/// A path's name in UTF-8.
inline std::string utf8FromPath(const std::filesystem::path& path) {
    const std::u8string name = path.u8string();
    return std::string(name.begin(), name.end());
}

/// std::fopen of a UTF-8 file name (nullptr and errno on failure, an invalid name included).
std::FILE* openFile(const std::string& name, const char* mode);

/// A UTF-8 file name opened for reading, as a descriptor for readSome() and closeFile() (binary,
/// not inherited by child processes); -1 and errno on failure, an invalid name included.
int openForReading(const std::string& name);

// --- Descriptors (the C runtime's on Windows, with 64-bit offsets): -1 and errno on failure.

/// read(): up to `size` bytes (Windows: at most 1 GiB a call); 0 at the end of the input.
std::int64_t readSome(int fd, char* data, std::size_t size);
/// write(): up to `size` bytes (Windows: at most 1 GiB a call).
std::int64_t writeSome(int fd, const char* data, std::size_t size);
/// lseek() with SEEK_SET, SEEK_CUR or SEEK_END.
std::int64_t seekTo(int fd, std::int64_t offset, int whence);
/// close().
int closeFile(int fd);

/// This process's id.
int processId();

// --- Files on disk.

/// A failed step on a file: what() is the system's reason ("No space left on device"), to be put
/// after the file's name by the caller; error() its errno, where it has one (else 0). exists(): the
/// step would have replaced a file that is kept.
class FileError : public std::runtime_error {
public:
    explicit FileError(const std::string& reason, int error = 0, bool exists = false)
        : std::runtime_error(reason), error_(error), exists_(exists) {}
    int error() const { return error_; }
    bool exists() const { return exists_; }

private:
    int error_;
    bool exists_;
};

/// Up to `limit` bytes of the file at `path` (UTF-8); nullopt when there is none (ENOENT). Throws
/// FileError when it is not a regular file (a FIFO would block) or cannot be opened or read.
std::optional<std::string> readUpTo(const std::string& path, std::size_t limit);

/// What identifies a file whatever names it (symbolic and hard links included): device and
/// inode on POSIX, volume serial number and file index on Windows.
struct FileIdentity {
    std::uint64_t device = 0;
    std::uint64_t index = 0;
    bool operator==(const FileIdentity&) const = default;
    /// An order, so that a std::map can be keyed by identities (written out: clang-tidy 14 takes a
    /// defaulted operator<=> for a literal 0 that wants nullptr).
    bool operator<(const FileIdentity& other) const {
        return device != other.device ? device < other.device : index < other.index;
    }
};
/// The identity of the existing file at `path` (through symbolic links), or nullopt when
/// nothing is there or it cannot be looked at.
std::optional<FileIdentity> fileIdentity(const std::string& path);

/// What is at a path: nothing, a folder, a regular file (with its permission bits; Windows has no
/// modes: 0) or another kind, or a symbolic link to nothing (with its target).
struct Found {
    enum Kind { Missing, Folder, Regular, Other, DanglingLink } kind = Missing;
    int mode = 0;
    std::string linkTarget = {};  // of a DanglingLink
};
/// What is at `path` now (through symbolic links). Throws FileError when it cannot be looked at.
Found lookUp(const std::string& path);

/// Why a file named `name` (UTF-8) cannot be made in `folder` for its length, or "": the file
/// system's limit in bytes (POSIX), 255 UTF-16 characters (Windows).
std::string nameLengthProblem(const std::string& folder, const std::string& name);

/// Whether the folder's permissions let this process make files in it. Windows: true (access()
/// does not read a folder's permissions, its ACLs; a writer finds out by trying).
bool folderWritable(const std::string& folder);

/// Makes a folder's new names durable; best effort, since the data is already in place (Windows
/// writes them through when they are made, with MOVEFILE_WRITE_THROUGH: nothing to do).
void syncFolder(const std::string& folder);

// --- Publishing a file atomically (files/atomic_file.hpp is the writer the formats use).

/// The start of the hidden names beside `path`: ".NAME.tmp-", where NAME is the file's name cut to
/// 200 bytes (at a character's start), so a hidden name fits every file system's limit (255)
/// whenever the name itself does. A hidden name is this and six random letters or digits.
std::string hiddenPrefix(const std::string& path);
/// Six random letters and digits, different in every process and call.
std::string randomSuffix();

/// Removes hidden files (`prefix` and six characters) in the folder that no live writer holds
/// (locked on POSIX, open without delete sharing on Windows): what a writer killed between creating
/// and publishing its file left behind. Files changed in the last few seconds are left alone.
void removeStaleTemporaries(const std::string& folder, const std::string& prefix);

/// A file being written before it has its name. Linux: an unnamed file (O_TMPFILE), linked by
/// /proc/self/fd when published, or where the file system has none a hidden name, locked while it
/// is written. Windows: always the hidden name, held open without delete sharing (so no other
/// writer's clean-up removes it) and written through a CRT descriptor, published with MoveFileExW.
/// Every method throws FileError; the destructor removes what was not published.
class PendingFile {
public:
    /// Creates the file in `folder`; its hidden names, where it needs them, start with `prefix`.
    PendingFile(const std::string& folder, const std::string& prefix);
    ~PendingFile();
    PendingFile(const PendingFile&) = delete;
    PendingFile& operator=(const PendingFile&) = delete;

    /// Where the data is written until prepare().
    int descriptor() const;
    /// The data flushed to the disk. POSIX: given the permission bits `mode` (or, with -1, 0666
    /// minus the umask, as open() gives a new file), synced and closed (checked: some file systems
    /// report write errors only there). Windows: committed; publish() closes it.
    void prepare(int mode);
    /// The prepared file gets the name `target`: replacing a file there, or with `replace` false
    /// failing (FileError with exists()) if a file appeared there meanwhile.
    void publish(const std::string& target, bool replace);
    /// Before publish() with replace: the file now at `target` gets a second, hidden name (a hard
    /// link where the file system has them, else it is moved there; held locked or open so no
    /// other writer's clean-up removes it), so that withdraw() can put it back. Nothing happens
    /// when no file is there.
    void setAside(const std::string& target);
    /// After publish(): the file set aside is put back at `target` (or, when none was, the
    /// published file is removed again, if it is still the one at `target`). Best effort.
    void withdraw(const std::string& target) noexcept;
    /// Once the file and its companions are published: the hidden name of the file set aside goes.
    void dropSetAside() noexcept;

private:
    struct State;
    std::unique_ptr<State> state_;
};

/// A file with no name in `folder`, open for reading and writing, for data a writer sets aside
/// until it goes into its published file (a streamed mesh's faces): nothing is ever left of it,
/// whatever happens to the process. Linux: O_TMPFILE, or where the file system has none a hidden name
/// (`prefix` and six characters) removed as soon as it is made. Windows: a hidden name, open for this
/// process alone, that the system deletes when it is closed (FILE_FLAG_DELETE_ON_CLOSE, also when the
/// process dies), kept in memory where it can be (FILE_ATTRIBUTE_TEMPORARY). Returns a descriptor
/// for readSome(), writeSome(), seekTo() and closeFile(). Throws FileError.
int openScratchFile(const std::string& folder, const std::string& prefix);

// --- Memory.

/// What the system lets this process allocate beyond what it holds: the limits of ulimit (address
/// space, data) and of every cgroup from this process's up (Linux); a job object's limits, the
/// job's less its peak use (Windows). UINT64_MAX where nothing limits it.
std::uint64_t memoryHeadroom();
/// The physical memory available to programs now (MemAvailable), in bytes; 0 where the system
/// does not say.
std::uint64_t availableMemory();
/// The process's peak resident memory, in bytes (0 where the system does not say): what the
/// command's --stats prints.
std::uint64_t peakMemoryBytes();
/// Gives the pages of freed blocks back to the system (malloc_trim; Windows: _heapmin). glibc keeps
/// them otherwise, scattered between live blocks in its per-thread arenas, and the next stage of a
/// bake would add its memory to theirs.
void releaseFreedMemory();

// --- Processes and the console.

/// The processors this process may run on (a cgroup's cpuset, taskset, a scheduler's binding;
/// Windows: its affinity mask), or 0 where the system does not say.
int processorCount();

/// Calls `handler` (which may only set an atomic flag) on Ctrl-C, SIGTERM and SIGHUP (a closed
/// terminal or a dropped SSH session); Windows: Ctrl-C, Ctrl-Break and a closed console window
/// (Windows stops the process shortly after that one). The process's default reaction is replaced.
void onInterrupt(void (*handler)());

/// Whether standard error is a terminal that draws escape codes (Windows 10 and later, once asked:
/// this asks).
bool stderrIsTerminal();

/// Windows only (the command's wmain; platform_windows.cpp): its UTF-16 arguments as UTF-8, the
/// toolkit's file names; the console is switched to show UTF-8 too. (Windows hands narrow arguments
/// in the ANSI code page, which cannot hold every file name.)
std::vector<std::string> utf8Arguments(int argc, const wchar_t* const* wideArgv);

/// The path of the running program, in UTF-8. Throws std::runtime_error when the system does not say.
std::string executablePath();

/// popen(): `command` started by the system's shell, its standard output (with its standard
/// error joined) to be read from the stream; nullptr when it cannot be started.
std::FILE* openCommand(const std::string& command);
/// pclose(): waits for the command; its exit code, or -1 when it did not exit by itself (a signal).
int closeCommand(std::FILE* pipe);

/// What runCommand saw: the command's exit code (0: it succeeded; -1: it did not exit by itself)
/// and what it wrote to standard output and standard error.
struct CommandOutput {
    int exitCode = -1;
    std::string output;
};
/// Runs `command` by the system's shell (openCommand). Throws std::runtime_error when it cannot be
/// started.
CommandOutput runCommand(const std::string& command);

}  // namespace dqj::platform
