// atomic_file.hpp - write a file under a temporary name in its folder, then rename it into place.
//
// Internal to libdqjulia (not exported). Every writer (images, and later VDB grids and meshes)
// writes to tempPath() and calls commit(): a failure or an exception before commit() never
// leaves a partial file and never destroys an existing file at the final path, because rename()
// within one folder is atomic.
#pragma once

#include <string>

namespace dqj {

class AtomicFile {
public:
    /// Creates an empty, uniquely named temporary file next to `path` (".name.tmp-XXXXXX").
    /// Throws std::runtime_error ("cannot write 'path': reason") if the folder is missing or
    /// not writable.
    explicit AtomicFile(std::string path);
    /// Removes the temporary file unless commit() succeeded.
    ~AtomicFile();

    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// The final path given to the constructor.
    const std::string& path() const { return path_; }
    /// Where the writer puts the data. The file exists (empty) and no descriptor is held open,
    /// so a writer may open it by name (libpng, OpenEXR, OpenVDB all do).
    const std::string& tempPath() const { return tempPath_; }

    /// Flushes the temporary file to disk, gives it the usual permissions (0666 minus the
    /// umask, as a plain open() would) and renames it to the final path. Throws
    /// std::runtime_error with the path and the reason on failure.
    void commit();

    /// "cannot write 'path': reason" - the message writers use for their own failures too.
    static std::string failureMessage(const std::string& path, const std::string& reason);
    /// The extension of a path's file name in lower case, with its dot (".vdb"), or "".
    static std::string lowercaseExtension(const std::string& path);

private:
    std::string path_;
    std::string tempPath_;
    bool committed_ = false;
};

}  // namespace dqj
