// Checked reading and atomic writing of OpenVDB files (vdb_file.hpp).
#include "files/vdb_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <openvdb/io/Archive.h>
#include <openvdb/io/Stream.h>

#include "platform/platform.hpp"
#include "files/message_text.hpp"

// Without Blosc, OpenVDB would throw only at the first leaf it compresses, in every bake.
#ifndef OPENVDB_USE_BLOSC
#error "dqjulia writes Blosc-compressed VDB files: OpenVDB must be built with Blosc (scripts/build-deps.sh)"
#endif

namespace dqj {
namespace {

/// Walks the container of a VDB file (header, file metadata, grid descriptors) and checks that
/// every length and offset in it stays inside the file, without allocating anything.
/// Returns an empty string or what is wrong.
std::string checkVdbContainer(std::istream& in, std::uint64_t size) {
    std::uint64_t position = 0;
    auto read = [&](void* data, std::uint64_t bytes) {
        if (bytes > size - position) return false;
        in.read(static_cast<char*>(data), std::streamsize(bytes));
        position += bytes;
        return bool(in);
    };
    auto skip = [&](std::uint64_t bytes) {
        if (bytes > size - position) return false;
        position += bytes;
        in.seekg(std::streamoff(position));
        return bool(in);
    };
    auto skipString = [&] {
        std::uint32_t length = 0;
        return read(&length, 4) && skip(length);
    };
    auto skipMetadata = [&] {
        std::int32_t count = 0;
        if (!read(&count, 4) || count < 0) return false;
        for (std::int32_t index = 0; index < count; ++index) {
            std::uint32_t bytes = 0;
            if (!skipString() || !skipString() || !read(&bytes, 4) || !skip(bytes)) return false;
        }
        return true;
    };
    std::int64_t magic = 0;
    std::uint32_t version = 0, major = 0, minor = 0;
    char hasOffsets = 0;
    if (!read(&magic, 8) || magic != openvdb::OPENVDB_MAGIC) return "not an OpenVDB file";
    if (!read(&version, 4) || version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION ||
        version > openvdb::OPENVDB_FILE_VERSION)
        return "unsupported OpenVDB file version " + std::to_string(version) + " (dqjulia reads versions " +
               std::to_string(openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) + " to " +
               std::to_string(openvdb::OPENVDB_FILE_VERSION) + ")";
    if (!read(&major, 4) || !read(&minor, 4) || !read(&hasOffsets, 1) || !skip(36))
        return "the file is truncated (in its header)";
    if (!hasOffsets) return "the file was written as a stream without grid offsets";
    if (!skipMetadata()) return "the file is truncated or damaged (in its metadata)";
    std::int32_t grids = 0;
    if (!read(&grids, 4) || grids < 0 || std::uint64_t(grids) > size / 16)
        return "the file is truncated or damaged (its grid count)";
    for (std::int32_t index = 0; index < grids; ++index) {
        std::int64_t gridStart = 0, blockStart = 0, end = 0;
        if (!skipString() || !skipString() || !skipString() || !read(&gridStart, 8) || !read(&blockStart, 8) ||
            !read(&end, 8))
            return "the file is truncated or damaged (grid " + std::to_string(index + 1) + "'s descriptor)";
        if (gridStart < std::int64_t(position) || blockStart < gridStart || end < blockStart ||
            std::uint64_t(end) > size)
            return "the file is truncated (grid " + std::to_string(index + 1) + " of " + std::to_string(grids) +
                   " ends at byte " + std::to_string(end) + " of a file of " + std::to_string(size) + " bytes)";
        position = std::uint64_t(end);
        in.seekg(std::streamoff(position));
        if (!in) return "the file is truncated";
    }
    return "";
}

/// OpenVDB's messages quote file contents and can be enormous: the first line, shortened.
std::string shortMessage(const std::string& text) {
    std::string line = text.substr(0, text.find('\n'));
    if (line.size() > 200) line = line.substr(0, 197) + "...";
    return line.empty() ? "the file is damaged" : line;
}

/// OpenVDB's file writer, aimed at AtomicFile's checked stream. io::File::write opens its own
/// std::ofstream and never checks it (a full disk gave a truncated file and no error);
/// Archive's seekable stream writer is what io::File::write calls, so the bytes are the same.
class CheckedVdbWriter : public openvdb::io::Archive {
public:
    explicit CheckedVdbWriter(std::uint32_t compression) { setCompression(compression); }
    void writeTo(std::ostream& out, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& metadata) const {
        openvdb::io::Archive::write(out, grids, /*seekable=*/true, metadata);
    }
};

}  // namespace

namespace {

/// Reads `path` with its container checked first: the metadata, and the grids unless
/// `metadataOnly`.
VdbContents readChecked(const std::string& path, bool metadataOnly) {
    openvdb::initialize();
    auto fail = [&](const std::string& reason) {
        return std::runtime_error("cannot read '" + inputExcerpt(path) + "': " + reason);
    };
    const std::filesystem::path name = platform::pathFromUtf8(path);  // UTF-8, on Windows too (platform.hpp)
    std::ifstream in(name, std::ios::binary);
    if (!in) throw fail(std::strerror(errno));
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(name, error);  // fails for all but regular files
    if (error || !std::filesystem::is_regular_file(name, error)) throw fail("not a regular file");
    const std::string problem = checkVdbContainer(in, std::uint64_t(size));
    if (!problem.empty()) throw fail(problem);
    in.clear();
    in.seekg(0);
    // Any read past the end now throws at once, instead of OpenVDB going on with garbage.
    in.exceptions(std::ios::badbit | std::ios::failbit | std::ios::eofbit);
    VdbContents contents;
    try {
        if (metadataOnly) {
            // The header and the file's metadata come first: read as io::Stream reads them.
            struct HeaderReader : openvdb::io::Archive {
                using Archive::readHeader;
            };
            HeaderReader reader;
            reader.readHeader(in);
            auto streamMetadata = std::make_shared<openvdb::io::StreamMetadata>();
            openvdb::io::setStreamMetadataPtr(in, streamMetadata, /*transfer=*/false);
            openvdb::io::setVersion(in, reader.libraryVersion(), reader.fileVersion());
            openvdb::io::setDataCompression(in, reader.compression());
            contents.metadata = std::make_shared<openvdb::MetaMap>();
            contents.metadata->readMeta(in);
        } else {
            openvdb::io::Stream stream(in, /*delayLoad=*/false);
            contents.metadata = stream.getMetadata();
            contents.grids = stream.getGrids();
        }
    } catch (const std::ios_base::failure&) {
        throw fail("the file is truncated or damaged (a grid's data ends early)");
    } catch (const std::bad_alloc&) {
        throw fail("the file is damaged (its grids claim more memory than there is)");
    } catch (const std::exception& error) {
        throw fail(shortMessage(error.what()));
    }
    if (!contents.metadata) contents.metadata = std::make_shared<openvdb::MetaMap>();
    if (!contents.grids) contents.grids = std::make_shared<openvdb::GridPtrVec>();
    return contents;
}

}  // namespace

VdbContents readVdbFile(const std::string& path) { return readChecked(path, false); }

openvdb::MetaMap::Ptr readVdbMetadata(const std::string& path) { return readChecked(path, true).metadata; }

openvdb::GridBase::Ptr findGrid(const VdbContents& contents, const std::string& name) {
    for (const openvdb::GridBase::Ptr& grid : *contents.grids)
        if (grid && grid->getName() == name) return grid;
    return nullptr;
}

std::uint32_t vdbCompressionFlags(VdbCompression compression) {
    switch (compression) {
        case VdbCompression::Blosc: return openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK;
        case VdbCompression::Zip: return openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK;
        case VdbCompression::None: break;
    }
    return openvdb::io::COMPRESS_ACTIVE_MASK;
}

void writeVdbFile(AtomicFile& file, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& metadata,
                  VdbCompression compression) {
    try {
        CheckedVdbWriter(vdbCompressionFlags(compression)).writeTo(file.stream(), grids, metadata);
    } catch (const openvdb::Exception& error) {
        if (!file.stream()) file.commit();  // throws with the write's reason ("No space left on device")
        throw std::runtime_error(AtomicFile::failureMessage(file.path(), error.what()));
    }
    file.commit();
}

}  // namespace dqj
