// atomic_file.hpp - the one checked, atomic file writer every format uses.
//
// Internal to libdqjulia (not exported). A writer puts its bytes into stream() and calls
// commit(). Until commit() the data lives in an unnamed file in the target's folder
// (O_TMPFILE), so a crash, SIGKILL or power loss leaves nothing behind; where the file
// system has no O_TMPFILE, a hidden ".name.tmp-XXXXXX" is used instead, locked while it is
// written, and removed by the next writer into that folder if its writer died. Every write,
// the final flush, fsync and close are checked before the file is published under its name,
// so a full disk or a failing device is an error ("No space left on device"), never a
// truncated file. commit() either replaces an existing file (Existing::Replace) or refuses to
// (Existing::Keep, atomically: a file created meanwhile by someone else is never replaced).
// Names are UTF-8 (platform.hpp). Windows has no unnamed files: there the hidden name is always
// used, held open so that no other writer removes it, and published with MoveFileExW. The steps on
// the file system are platform::PendingFile's; the checks and their order are here.
// AtomicFileSet publishes the several files of one run together: all of them or none.
// ScratchFile holds data a writer sets aside until it goes into its AtomicFile (a streamed mesh's
// faces, which follow all of its vertices), or reads back itself: a file without a name beside
// the target, gone whatever happens.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "dqjulia/params.hpp"  // Existing
#include "files/message_text.hpp"  // printableText, inputExcerpt

namespace dqj {

/// Why Windows cannot hold a file at `path` under the name given, or "": a component that is a
/// reserved device name (CON, PRN, AUX, NUL, COM1-COM9, LPT1-LPT9, COM and LPT with a superscript
/// 1-3, CONIN$, CONOUT$; any case, with any extension, spaces before the extension too), holds a
/// character Windows does not allow in names (< > : " | ? * and control characters; a colon names a
/// stream of another file), or ends in a dot or a space (which Windows drops, so the file would get
/// another name); and the device namespace (\\.\). A drive ("C:") and a UNC share
/// (\\server\share) are the path's root, not components. Pure string logic, so it is tested on
/// every platform; the writers apply it on Windows.
std::string windowsNameProblem(const std::string& path);
/// Why this system cannot hold a file at `path` under the name given, or "": windowsNameProblem()
/// on Windows; nothing on POSIX, where a name is bytes (its length is checked when it is written).
std::string systemNameProblem(const std::string& path);

class AtomicFile {
public:
    /// Opens the temporary file in the folder of `path`. Throws std::runtime_error ("cannot
    /// write 'path': reason") if the folder is missing or not writable, if `path` is a folder
    /// or another non-regular file (a device, FIFO or socket), or if it exists and `existing`
    /// is Keep.
    explicit AtomicFile(std::string path, Existing existing = Existing::Replace);
    /// Discards the data unless commit() succeeded.
    ~AtomicFile();

    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// The final path given to the constructor.
    const std::string& path() const { return path_; }
    /// Where the writer puts the data: buffered, seekable, every write checked (the first
    /// failure is kept and reported by commit()).
    std::ostream& stream();

    /// Throws std::runtime_error with the reason of the first failed write ("No space left on
    /// device"), if one failed: for writers whose format library reports a failure without it.
    void checkWrites();

    /// Checks every write, flushes, fsyncs and closes the file, gives it the usual
    /// permissions (0666 minus the umask, or those of the file it replaces) and publishes it
    /// under path(). Throws std::runtime_error with the path and the reason on failure; the
    /// previous file at path() is then untouched.
    void commit();

    /// "cannot write 'path': reason" - the message writers use for their own failures too.
    static std::string failureMessage(const std::string& path, const std::string& reason);
    /// The extension of a path's file name in lower case, with its dot (".vdb"), or "". Throws
    /// std::runtime_error for a name that is not UTF-8 where names must be (Windows).
    static std::string lowercaseExtension(const std::string& path);

    struct State;

private:
    friend class AtomicFileSet;
    /// commit()'s first part: every write checked, the data flushed to the disk (and, on POSIX,
    /// the file closed); what can fail for lack of space fails here, before any name changes.
    void prepare();
    /// commit()'s second part: the prepared file gets its name. Throws as commit() does.
    void publish();
    /// Before publish() with Replace: the file now at path() gets a second, hidden name (a hard
    /// link where the file system has them, else it is moved there; held locked or open so no other
    /// writer's clean-up removes it), so that withdraw() can put it back. Nothing happens when no
    /// file is there. Throws std::runtime_error when it cannot be done.
    void setAside();
    /// After publish(): the file set aside is put back at path() (or, when none was, the
    /// published file is removed again, if it is still the one at path()). Best effort: a
    /// failure leaves the published file.
    void withdraw() noexcept;
    /// Once the set is published: the hidden name of the file set aside is removed.
    void dropSetAside() noexcept;

    std::string path_;
    std::unique_ptr<State> state_;
};

/// Data set aside and later appended to an AtomicFile: a file in the folder of `path` (the
/// target's disk, not /tmp's, which may be memory) that has no name, so nothing is ever left of it
/// (platform::openScratchFile). Writes are buffered and checked as AtomicFile's.
class ScratchFile {
public:
    /// Throws std::runtime_error ("cannot write 'path': reason") when the folder takes no file.
    explicit ScratchFile(const std::string& path);
    ~ScratchFile();
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;

    std::ostream& stream();
    /// Throws std::runtime_error with the reason of the first failed write, if one failed.
    void checkWrites();
    /// Appends everything written so far to `target`'s stream. Throws std::runtime_error when a
    /// write here failed or the data cannot be read back.
    void appendTo(AtomicFile& target);
    /// Hands everything written so far to `consume` in blocks of up to a megabyte, from the start
    /// (again at each call). Throws as appendTo.
    void readBack(const std::function<void(const char* data, std::size_t size)>& consume);

    struct State;

private:
    std::string path_;
    std::unique_ptr<State> state_;
};

/// The files one run writes, published together: all of them or none. Each member is written
/// like an AtomicFile (its data in a temporary file until the end). commit() prepares every
/// member first (every write, flush and fsync checked: a full disk fails here, with nothing
/// published), then gives each its name; if that fails for one (a file that appeared meanwhile
/// without --force, an error of the file system), the members already published are withdrawn
/// and the files they replaced are put back under their names, so the folders hold what they
/// held before. Until commit() succeeds nothing is published, and destroying the set discards
/// every temporary file. (A replaced file stays reachable under a hidden, locked second name
/// until the whole set is published; where a file system has no hard links, and on Windows, it
/// is moved there, so its name is missing for the instant before the new file takes it.)
class AtomicFileSet {
public:
    explicit AtomicFileSet(Existing existing = Existing::Replace);
    ~AtomicFileSet();
    AtomicFileSet(const AtomicFileSet&) = delete;
    AtomicFileSet& operator=(const AtomicFileSet&) = delete;

    /// A new member for `path`, its temporary file opened now (throws as AtomicFile's constructor).
    AtomicFile& add(const std::string& path);
    /// Publishes every member, all or none. Throws std::runtime_error with the path and the
    /// reason of the first failure.
    void commit();
    /// The members' paths, in the order they were added.
    std::vector<std::string> paths() const;

private:
    Existing existing_;
    std::vector<std::unique_ptr<AtomicFile>> files_;
};

}  // namespace dqj
