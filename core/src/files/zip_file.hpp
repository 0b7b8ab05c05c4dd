// zip_file.hpp - a ZIP archive written into an AtomicFile entry by entry, each entry's data
// deflated as it comes (the 3MF's package, mesh_3mf.hpp; internal to libdqjulia).
//
// Written on the zlib the project links already (raw deflate, CRC-32). An entry's local header
// is written before its data with room for its sizes and CRC, which are patched in once the entry
// ends (the AtomicFile's stream can seek), so no data descriptor is needed. The local header always
// carries a ZIP64 extra field (its 32-bit sizes 0xFFFFFFFF), so an entry may pass 4 GB without
// knowing it beforehand; the central directory uses ZIP64 fields and the ZIP64 end records only
// where a size, an offset or the directory passes 4 GB, so a small archive is a plain one. Names
// are ASCII; times are 1980-01-01 00:00 (the same mesh gives the same bytes).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "files/atomic_file.hpp"

namespace dqj {

class ZipWriter {
public:
    /// Writes the archive from the current end of `file`'s stream (an empty file).
    explicit ZipWriter(AtomicFile& file);
    ~ZipWriter();
    ZipWriter(const ZipWriter&) = delete;
    ZipWriter& operator=(const ZipWriter&) = delete;

    /// Starts an entry named `name` (ASCII, '/' between folders); ends the one before, if any.
    void begin(const std::string& name);
    /// Appends to the current entry's data.
    void write(const char* data, std::size_t size);
    void write(const std::string& text) { write(text.data(), text.size()); }
    /// Ends the last entry and writes the central directory: the archive is complete. Throws
    /// std::runtime_error when a write failed.
    void finish();

private:
    struct Entry {
        std::string name;
        std::uint64_t offset = 0, compressed = 0, size = 0;
        std::uint32_t crc = 0;
    };
    void endEntry();
    /// Deflates what is in the stream's input with `flush`, writing what comes out.
    void deflateInput(int flush);
    void put(const std::string& bytes);

    AtomicFile& file_;
    struct Deflater;
    std::unique_ptr<Deflater> deflater_;
    std::vector<Entry> entries_;
    bool open_ = false;         // an entry is being written
    std::uint64_t offset_ = 0;  // bytes of the archive so far
};

}  // namespace dqj
