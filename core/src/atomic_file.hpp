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
// Names are UTF-8 (file_names.hpp). Windows has no unnamed files: there the hidden name is always
// used, held open so that no other writer removes it, and published with MoveFileExW.
#pragma once

#include <memory>
#include <ostream>
#include <string>

#include "dqjulia/params.hpp"  // Existing
#include "message_text.hpp"    // printableText, inputExcerpt

namespace dqj {

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
    std::string path_;
    std::unique_ptr<State> state_;
};

}  // namespace dqj
