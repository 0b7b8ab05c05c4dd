// platform.hpp on Windows (MinGW-w64). Files: the C runtime's descriptors over UTF-16 names; a file
// being published has a hidden name ".name.tmp-XXXXXX", held open without delete sharing (so no
// other writer's clean-up can remove it), and gets its name with MoveFileExW: MOVEFILE_REPLACE_EXISTING
// to replace, and without it to keep, where it fails if the name exists. Memory: job objects and
// GlobalMemoryStatusEx. Processors: the affinity mask. Console: SetConsoleCtrlHandler.
#include "platform/platform.hpp"

#include <fcntl.h>
#include <io.h>
#include <process.h>
#include <windows.h>
#define PSAPI_VERSION 2  // GetProcessMemoryInfo from kernel32.dll, not psapi.dll
#include <malloc.h>
#include <psapi.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <system_error>

namespace dqj::platform {
namespace {

FileError systemError(int error) { return FileError(std::strerror(error), error); }

/// A Win32 error code's text, in UTF-8.
std::string windowsMessage(DWORD error) {
    wchar_t* text = nullptr;
    const DWORD length =
        ::FormatMessageW(FORMAT_MESSAGE_ALLOCATE_BUFFER | FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS,
                         nullptr, error, 0, reinterpret_cast<wchar_t*>(&text), 0, nullptr);
    std::string message = length ? utf8FromPath(std::filesystem::path(std::wstring(text, length)))
                                 : "Windows error " + std::to_string(error);
    if (text) ::LocalFree(text);
    while (!message.empty() && (message.back() == '\n' || message.back() == '\r' || message.back() == '.'))
        message.pop_back();
    return message;
}
FileError windowsError(DWORD error) { return FileError(windowsMessage(error)); }

void closeHandle(HANDLE& handle) {
    if (handle != INVALID_HANDLE_VALUE) ::CloseHandle(handle);
    handle = INVALID_HANDLE_VALUE;
}

/// A new hidden name in `folder`.
std::string hiddenName(const std::string& folder, const std::string& prefix) {
    return utf8FromPath(pathFromUtf8(folder) / pathFromUtf8(prefix + randomSuffix()));
}

void (*interruptHandler)() = nullptr;

/// Ctrl-C, Ctrl-Break and a closed console window (Windows stops the process shortly after that one).
BOOL WINAPI onConsoleEvent(DWORD event) {
    if (event != CTRL_C_EVENT && event != CTRL_BREAK_EVENT && event != CTRL_CLOSE_EVENT) return FALSE;
    if (interruptHandler) interruptHandler();
    return TRUE;
}

}  // namespace

std::FILE* openFile(const std::string& name, const char* mode) {
    try {
        const std::wstring wideMode(mode, mode + std::char_traits<char>::length(mode));
        return ::_wfopen(pathFromUtf8(name).c_str(), wideMode.c_str());
    } catch (const std::filesystem::filesystem_error&) {
        errno = EINVAL;
        return nullptr;
    }
}

int openForReading(const std::string& name) {
    try {
        return ::_wopen(pathFromUtf8(name).c_str(), _O_RDONLY | _O_BINARY | _O_NOINHERIT);
    } catch (const std::filesystem::filesystem_error&) {
        errno = EINVAL;
        return -1;
    }
}

std::int64_t readSome(int fd, char* data, std::size_t size) {
    return ::_read(fd, data, unsigned(std::min<std::size_t>(size, std::size_t(1) << 30)));
}
std::int64_t writeSome(int fd, const char* data, std::size_t size) {
    return ::_write(fd, data, unsigned(std::min<std::size_t>(size, std::size_t(1) << 30)));
}
std::int64_t seekTo(int fd, std::int64_t offset, int whence) { return ::_lseeki64(fd, offset, whence); }
int closeFile(int fd) { return ::_close(fd); }
int processId() { return ::_getpid(); }

std::optional<FileIdentity> fileIdentity(const std::string& path) {
    HANDLE handle = INVALID_HANDLE_VALUE;
    try {
        handle = ::CreateFileW(pathFromUtf8(path).c_str(), 0, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE,
                               nullptr, OPEN_EXISTING, FILE_FLAG_BACKUP_SEMANTICS, nullptr);
    } catch (const std::filesystem::filesystem_error&) {
        return std::nullopt;  // not UTF-8: no file has that name
    }
    if (handle == INVALID_HANDLE_VALUE) return std::nullopt;
    BY_HANDLE_FILE_INFORMATION information{};
    const bool known = ::GetFileInformationByHandle(handle, &information);
    closeHandle(handle);
    if (!known) return std::nullopt;
    return FileIdentity{information.dwVolumeSerialNumber,
                        (std::uint64_t(information.nFileIndexHigh) << 32) | information.nFileIndexLow};
}

Found lookUp(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code error;
    const fs::file_status status = fs::status(pathFromUtf8(path), error);
    if (status.type() == fs::file_type::not_found) {
        std::error_code linkError;
        if (fs::is_symlink(fs::symlink_status(pathFromUtf8(path), linkError)))
            return {Found::DanglingLink, 0, utf8FromPath(fs::read_symlink(pathFromUtf8(path), linkError))};
        return {Found::Missing, 0};
    }
    if (error) throw FileError(error.message());
    if (status.type() == fs::file_type::directory) return {Found::Folder, 0};
    return {status.type() == fs::file_type::regular ? Found::Regular : Found::Other, 0};
}

std::string nameLengthProblem(const std::string&, const std::string& name) {
    if (pathFromUtf8(name).wstring().size() > 255)
        return "the file name is longer than Windows allows (255 characters)";
    return "";
}

bool folderWritable(const std::string&) { return true; }

void syncFolder(const std::string&) {}

void removeStaleTemporaries(const std::string& folder, const std::string& prefix) {
    namespace fs = std::filesystem;
    std::error_code error;
    const auto now = fs::file_time_type::clock::now();
    for (const auto& entry : fs::directory_iterator(pathFromUtf8(folder), error)) {
        const std::string name = utf8FromPath(entry.path().filename());
        if (name.rfind(prefix, 0) != 0 || name.size() != prefix.size() + 6) continue;
        std::error_code entryError;
        if (!entry.is_regular_file(entryError)) continue;
        // A live writer's file cannot be deleted: it is open without delete sharing.
        const auto changed = entry.last_write_time(entryError);
        if (!entryError && changed + std::chrono::seconds(5) < now) ::DeleteFileW(entry.path().c_str());
    }
}

struct PendingFile::State {
    std::string folder;
    std::string prefix;
    int fd = -1;
    std::string tempPath;
    bool published = false;
    std::string asidePath;  // the hidden second name of the file this one replaces (setAside), or ""
    HANDLE asideHandle = INVALID_HANDLE_VALUE;  // holds the file set aside: no other writer deletes it
};

int openScratchFile(const std::string& folder, const std::string& prefix) {
    // A new hidden name (CREATE_NEW), shared with no one, deleted by the system when closed.
    HANDLE handle = INVALID_HANDLE_VALUE;
    DWORD error = ERROR_FILE_EXISTS;
    for (int attempt = 0; attempt < 100 && handle == INVALID_HANDLE_VALUE && error == ERROR_FILE_EXISTS; ++attempt) {
        handle = ::CreateFileW(pathFromUtf8(hiddenName(folder, prefix)).c_str(), GENERIC_READ | GENERIC_WRITE, 0,
                               nullptr, CREATE_NEW,
                               FILE_ATTRIBUTE_HIDDEN | FILE_ATTRIBUTE_TEMPORARY | FILE_FLAG_DELETE_ON_CLOSE, nullptr);
        if (handle == INVALID_HANDLE_VALUE) error = ::GetLastError();
    }
    if (handle == INVALID_HANDLE_VALUE) throw windowsError(error);
    const int fd = ::_open_osfhandle(reinterpret_cast<intptr_t>(handle), _O_BINARY);
    if (fd < 0) {
        ::CloseHandle(handle);  // deletes it
        throw FileError("cannot open the scratch file");
    }
    return fd;
}

PendingFile::PendingFile(const std::string& folder, const std::string& prefix) : state_(std::make_unique<State>()) {
    State& state = *state_;
    state.folder = folder;
    state.prefix = prefix;
    // A new hidden name (CREATE_NEW never opens an existing file), open for this writer alone.
    HANDLE handle = INVALID_HANDLE_VALUE;
    DWORD error = ERROR_FILE_EXISTS;
    for (int attempt = 0; attempt < 100 && handle == INVALID_HANDLE_VALUE && error == ERROR_FILE_EXISTS; ++attempt) {
        state.tempPath = hiddenName(folder, prefix);
        handle = ::CreateFileW(pathFromUtf8(state.tempPath).c_str(), GENERIC_READ | GENERIC_WRITE, FILE_SHARE_READ,
                               nullptr, CREATE_NEW, FILE_ATTRIBUTE_NORMAL, nullptr);
        if (handle == INVALID_HANDLE_VALUE) error = ::GetLastError();
    }
    if (handle == INVALID_HANDLE_VALUE) {
        state.tempPath.clear();
        throw windowsError(error);
    }
    state.fd = ::_open_osfhandle(reinterpret_cast<intptr_t>(handle), _O_BINARY);
    if (state.fd < 0) {
        ::CloseHandle(handle);
        ::DeleteFileW(pathFromUtf8(state.tempPath).c_str());
        state.tempPath.clear();
        throw FileError("cannot open the temporary file");
    }
}

PendingFile::~PendingFile() {
    State& state = *state_;
    if (state.fd >= 0) ::_close(state.fd);
    if (!state.published && !state.tempPath.empty()) ::DeleteFileW(pathFromUtf8(state.tempPath).c_str());
    closeHandle(state.asideHandle);
}

int PendingFile::descriptor() const { return state_->fd; }

void PendingFile::prepare(int) {
    // Flushed to the disk (checked); publish() closes the file (checked) and names it.
    if (::_commit(state_->fd) != 0) throw systemError(errno);
}

void PendingFile::publish(const std::string& target, bool replace) {
    State& state = *state_;
    const int fd = state.fd;
    state.fd = -1;
    if (::_close(fd) != 0) throw systemError(errno);
    const DWORD flags = MOVEFILE_WRITE_THROUGH | (replace ? MOVEFILE_REPLACE_EXISTING : 0);
    if (!::MoveFileExW(pathFromUtf8(state.tempPath).c_str(), pathFromUtf8(target).c_str(), flags)) {
        const DWORD error = ::GetLastError();
        if (error == ERROR_ALREADY_EXISTS || error == ERROR_FILE_EXISTS)
            throw FileError(windowsMessage(error), 0, true);
        throw windowsError(error);
    }
    state.published = true;
}

void PendingFile::setAside(const std::string& target) {
    State& state = *state_;
    const std::filesystem::path name = pathFromUtf8(target);
    if (::GetFileAttributesW(name.c_str()) == INVALID_FILE_ATTRIBUTES) return;  // nothing there
    DWORD error = ERROR_FILE_EXISTS;
    for (int attempt = 0; attempt < 100 && error == ERROR_FILE_EXISTS; ++attempt) {
        const std::string aside = hiddenName(state.folder, state.prefix);
        if (::MoveFileExW(name.c_str(), pathFromUtf8(aside).c_str(), MOVEFILE_WRITE_THROUGH)) {
            state.asidePath = aside;
            // Open without delete sharing: no other writer's clean-up removes it meanwhile.
            state.asideHandle = ::CreateFileW(pathFromUtf8(aside).c_str(), GENERIC_READ, FILE_SHARE_READ, nullptr,
                                              OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
            return;
        }
        error = ::GetLastError();
        if (error == ERROR_ALREADY_EXISTS) error = ERROR_FILE_EXISTS;
    }
    throw windowsError(error);
}

void PendingFile::withdraw(const std::string& target) noexcept {
    State& state = *state_;
    const std::filesystem::path name = pathFromUtf8(target);
    closeHandle(state.asideHandle);
    if (!state.asidePath.empty()) {
        if (::MoveFileExW(pathFromUtf8(state.asidePath).c_str(), name.c_str(),
                          MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH))
            state.asidePath.clear();
    } else if (state.published) {
        ::DeleteFileW(name.c_str());
    }
}

void PendingFile::dropSetAside() noexcept {
    State& state = *state_;
    closeHandle(state.asideHandle);
    if (!state.asidePath.empty()) ::DeleteFileW(pathFromUtf8(state.asidePath).c_str());
    state.asidePath.clear();
}

std::uint64_t memoryHeadroom() {
    JOBOBJECT_EXTENDED_LIMIT_INFORMATION job{};
    if (!::QueryInformationJobObject(nullptr, JobObjectExtendedLimitInformation, &job, sizeof job, nullptr))
        return UINT64_MAX;  // not in a job
    std::uint64_t result = UINT64_MAX;
    const DWORD flags = job.BasicLimitInformation.LimitFlags;
    if (flags & JOB_OBJECT_LIMIT_PROCESS_MEMORY) result = std::min<std::uint64_t>(result, job.ProcessMemoryLimit);
    if (flags & JOB_OBJECT_LIMIT_JOB_MEMORY)
        result = std::min<std::uint64_t>(result, job.JobMemoryLimit > job.PeakJobMemoryUsed
                                                     ? job.JobMemoryLimit - job.PeakJobMemoryUsed
                                                     : 0);
    return result;
}

std::uint64_t availableMemory() {
    MEMORYSTATUSEX status{};
    status.dwLength = sizeof status;
    return ::GlobalMemoryStatusEx(&status) ? status.ullAvailPhys : 0;
}

std::uint64_t peakMemoryBytes() {
    PROCESS_MEMORY_COUNTERS counters{};
    return ::GetProcessMemoryInfo(::GetCurrentProcess(), &counters, sizeof counters) ? counters.PeakWorkingSetSize : 0;
}

void releaseFreedMemory() { ::_heapmin(); }

int processorCount() {
    DWORD_PTR process = 0, system = 0;
    if (!::GetProcessAffinityMask(::GetCurrentProcess(), &process, &system) || process == 0) return 0;
    int count = 0;
    for (; process; process &= process - 1) ++count;
    return count;
}

void onInterrupt(void (*handler)()) {
    interruptHandler = handler;
    ::SetConsoleCtrlHandler(onConsoleEvent, TRUE);
}

bool stderrIsTerminal() {
    const HANDLE console = ::GetStdHandle(STD_ERROR_HANDLE);
    DWORD mode = 0;
    return ::GetConsoleMode(console, &mode) && ::SetConsoleMode(console, mode | ENABLE_VIRTUAL_TERMINAL_PROCESSING);
}

std::vector<std::string> utf8Arguments(int argc, const wchar_t* const* wideArgv) {
    std::vector<std::string> arguments;
    for (int index = 0; index < argc; ++index) {
        const int bytes = ::WideCharToMultiByte(CP_UTF8, 0, wideArgv[index], -1, nullptr, 0, nullptr, nullptr);
        std::string argument(bytes > 0 ? std::size_t(bytes) : 1, '\0');
        ::WideCharToMultiByte(CP_UTF8, 0, wideArgv[index], -1, argument.data(), bytes, nullptr, nullptr);
        argument.resize(argument.size() - 1);  // the terminating NUL
        arguments.push_back(std::move(argument));
    }
    ::SetConsoleOutputCP(CP_UTF8);
    return arguments;
}

std::string executablePath() {
    std::wstring self(32768, L'\0');
    const DWORD length = ::GetModuleFileNameW(nullptr, self.data(), DWORD(self.size()));
    if (length == 0 || length >= self.size()) throw std::runtime_error("cannot find this dqjulia's path");
    self.resize(length);
    return utf8FromPath(std::filesystem::path(self));
}

std::FILE* openCommand(const std::string& command) { return ::_popen((command + " 2>&1").c_str(), "r"); }

int closeCommand(std::FILE* pipe) { return ::_pclose(pipe); }

}  // namespace dqj::platform
