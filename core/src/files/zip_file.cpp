// A ZIP archive written entry by entry, deflated as it comes (zip_file.hpp).
#include "files/zip_file.hpp"

#include <algorithm>
#include <stdexcept>

#include <zlib.h>

namespace dqj {
namespace {

constexpr std::uint32_t kMax32 = 0xFFFFFFFFu;
constexpr std::uint16_t kVersion = 45;  // ZIP64 (APPNOTE 4.4.3)
constexpr std::uint16_t kDeflate = 8;
constexpr std::uint16_t kDate1980 = (0 << 9) | (1 << 5) | 1;  // 1980-01-01: the first DOS date

/// Little-endian fields appended to a byte string.
struct Bytes {
    std::string data;
    Bytes& u16(std::uint64_t value) { return le(value, 2); }
    Bytes& u32(std::uint64_t value) { return le(value, 4); }
    Bytes& u64(std::uint64_t value) { return le(value, 8); }
    Bytes& text(const std::string& value) {
        data += value;
        return *this;
    }
    Bytes& le(std::uint64_t value, int size) {
        for (int byte = 0; byte < size; ++byte) data.push_back(char((value >> (8 * byte)) & 0xFF));
        return *this;
    }
};

}  // namespace

struct ZipWriter::Deflater {
    z_stream stream{};
    bool ready = false;
    std::vector<unsigned char> out = std::vector<unsigned char>(std::size_t(1) << 18);
    ~Deflater() {
        if (ready) deflateEnd(&stream);
    }
};

ZipWriter::ZipWriter(AtomicFile& file) : file_(file), deflater_(std::make_unique<Deflater>()) {
    offset_ = std::uint64_t(file_.stream().tellp());
}

ZipWriter::~ZipWriter() = default;

void ZipWriter::put(const std::string& bytes) {
    file_.stream().write(bytes.data(), std::streamsize(bytes.size()));
    offset_ += bytes.size();
}

void ZipWriter::begin(const std::string& name) {
    if (open_) endEntry();
    Entry entry;
    entry.name = name;
    entry.offset = offset_;
    entry.crc = std::uint32_t(crc32(0, nullptr, 0));
    entries_.push_back(entry);
    // The sizes and CRC are patched in by endEntry(): CRC at +14, the ZIP64 sizes at +30+name+4.
    put(Bytes()
            .u32(0x04034b50)
            .u16(kVersion)
            .u16(0)
            .u16(kDeflate)
            .u16(0)
            .u16(kDate1980)
            .u32(0)
            .u32(kMax32)
            .u32(kMax32)
            .u16(name.size())
            .u16(20)
            .text(name)
            .u16(0x0001)
            .u16(16)
            .u64(0)
            .u64(0)
            .data);
    Deflater& d = *deflater_;
    if (d.ready) deflateEnd(&d.stream);
    d.stream = z_stream{};
    // Raw deflate (no zlib header), level 1: text this size compresses about as well at level 1
    // as at 6, at several times the speed.
    if (deflateInit2(&d.stream, 1, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        throw std::runtime_error(AtomicFile::failureMessage(file_.path(), "zlib's deflate could not start"));
    d.ready = true;
    open_ = true;
}

void ZipWriter::deflateInput(int flush) {
    Deflater& d = *deflater_;
    Entry& entry = entries_.back();
    int status = Z_OK;
    do {
        d.stream.next_out = d.out.data();
        d.stream.avail_out = uInt(d.out.size());
        status = deflate(&d.stream, flush);
        if (status == Z_STREAM_ERROR) throw std::logic_error("ZipWriter: deflate failed");
        const std::size_t made = d.out.size() - d.stream.avail_out;
        file_.stream().write(reinterpret_cast<const char*>(d.out.data()), std::streamsize(made));
        offset_ += made;
        entry.compressed += made;
    } while (d.stream.avail_out == 0 || (flush == Z_FINISH && status != Z_STREAM_END));
}

void ZipWriter::write(const char* data, std::size_t size) {
    if (!open_) throw std::logic_error("ZipWriter::write: no entry begun");
    Entry& entry = entries_.back();
    while (size > 0) {
        const std::size_t piece = std::min<std::size_t>(size, std::size_t(1) << 30);
        entry.crc = std::uint32_t(crc32(entry.crc, reinterpret_cast<const Bytef*>(data), uInt(piece)));
        entry.size += piece;
        deflater_->stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data));
        deflater_->stream.avail_in = uInt(piece);
        deflateInput(Z_NO_FLUSH);
        data += piece;
        size -= piece;
    }
    file_.checkWrites();
}

void ZipWriter::endEntry() {
    deflater_->stream.next_in = nullptr;
    deflater_->stream.avail_in = 0;
    deflateInput(Z_FINISH);
    const Entry& entry = entries_.back();
    std::ostream& out = file_.stream();
    out.seekp(std::streamoff(entry.offset + 14));
    const std::string crc = Bytes().u32(entry.crc).data;
    out.write(crc.data(), 4);
    out.seekp(std::streamoff(entry.offset + 30 + entry.name.size() + 4));
    const std::string sizes = Bytes().u64(entry.size).u64(entry.compressed).data;
    out.write(sizes.data(), std::streamsize(sizes.size()));
    out.seekp(std::streamoff(offset_));
    file_.checkWrites();
    open_ = false;
}

void ZipWriter::finish() {
    if (open_) endEntry();
    const std::uint64_t directory = offset_;
    for (const Entry& entry : entries_) {
        // ZIP64 fields for what does not fit in 32 bits, in APPNOTE's order.
        Bytes wide;
        if (entry.size >= kMax32) wide.u64(entry.size);
        if (entry.compressed >= kMax32) wide.u64(entry.compressed);
        if (entry.offset >= kMax32) wide.u64(entry.offset);
        Bytes extra;
        if (!wide.data.empty()) extra.u16(0x0001).u16(wide.data.size()).text(wide.data);
        put(Bytes()
                .u32(0x02014b50)
                .u16(kVersion)
                .u16(kVersion)
                .u16(0)
                .u16(kDeflate)
                .u16(0)
                .u16(kDate1980)
                .u32(entry.crc)
                .u32(std::min<std::uint64_t>(entry.compressed, kMax32))
                .u32(std::min<std::uint64_t>(entry.size, kMax32))
                .u16(entry.name.size())
                .u16(extra.data.size())
                .u16(0)
                .u16(0)
                .u16(0)
                .u32(0)
                .u32(std::min<std::uint64_t>(entry.offset, kMax32))
                .text(entry.name)
                .text(extra.data)
                .data);
    }
    const std::uint64_t directorySize = offset_ - directory;
    const bool wide = directory >= kMax32 || directorySize >= kMax32 || entries_.size() >= 0xFFFF;
    if (wide) {
        const std::uint64_t record = offset_;
        put(Bytes()
                .u32(0x06064b50)
                .u64(44)
                .u16(kVersion)
                .u16(kVersion)
                .u32(0)
                .u32(0)
                .u64(entries_.size())
                .u64(entries_.size())
                .u64(directorySize)
                .u64(directory)
                .data);
        put(Bytes().u32(0x07064b50).u32(0).u64(record).u32(1).data);
    }
    put(Bytes()
            .u32(0x06054b50)
            .u16(0)
            .u16(0)
            .u16(std::min<std::size_t>(entries_.size(), 0xFFFF))
            .u16(std::min<std::size_t>(entries_.size(), 0xFFFF))
            .u32(std::min<std::uint64_t>(directorySize, kMax32))
            .u32(std::min<std::uint64_t>(directory, kMax32))
            .u16(0)
            .data);
    file_.checkWrites();
}

}  // namespace dqj
