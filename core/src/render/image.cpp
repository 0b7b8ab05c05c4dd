// Image files: 8- and 16-bit sRGB PNG through libpng, linear EXR with depth and normals
// through OpenEXR. Every write goes through AtomicFile, so a failed write leaves nothing behind.
#include "dqjulia/image.hpp"
#include "render/image_writer.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <stdexcept>
#include <vector>

#include <png.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <half.h>

#include "files/atomic_file.hpp"
#include "platform/platform.hpp"

namespace dqj {
namespace {

// ---------------------------------------------------------------- colour transfer

/// Linear -> sRGB-encoded value in [0, 1]; NaN and negatives become 0.
double encodeSrgb(double linear) {
    if (!(linear > 0.0)) return 0.0;
    if (linear >= 1.0) return 1.0;
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

/// The 8-bit code by the formula: sRGB-encoded, scaled, rounded (a pow per call).
int srgb8ByFormula(float linear) { return int(std::lround(encodeSrgb(linear) * 255.0)); }

/// linearToSrgb8 without a pow per call, and with the formula's codes for every float: `steps[k]`
/// is the smallest float whose code is k + 1 or more (found by bisection over the floats, the
/// formula being non-decreasing), and `start[b]` the code of the smallest positive float whose
/// top 16 bits are b. A float of [0, 1] starts from its bucket's code and steps up past the
/// steps it reaches: at most two (a bucket spans under 1 % of its value, a code at least 2 %).
struct Srgb8Table {
    static constexpr std::uint32_t kBuckets = (0x3F800000u >> 16) + 1;  // up to 1.0f
    std::array<float, 255> steps{};
    std::array<std::uint8_t, kBuckets> start{};

    Srgb8Table() {
        for (int code = 1; code <= 255; ++code) {
            std::uint32_t below = 0, at = 0x3F800000u;  // the bits of 0.0f (code 0) and 1.0f (255)
            while (at - below > 1) {
                const std::uint32_t middle = below + (at - below) / 2;
                (srgb8ByFormula(std::bit_cast<float>(middle)) >= code ? at : below) = middle;
            }
            steps[code - 1] = std::bit_cast<float>(at);
        }
        for (std::uint32_t bucket = 0; bucket < kBuckets; ++bucket)
            start[bucket] = std::uint8_t(srgb8ByFormula(std::bit_cast<float>(std::max(bucket << 16, 1u))));
    }

    std::uint8_t operator()(float linear) const {
        if (!(linear > 0.0f)) return 0;  // NaN and negatives, as encodeSrgb
        if (linear >= 1.0f) return 255;
        int code = start[std::bit_cast<std::uint32_t>(linear) >> 16];
        while (code < 255 && linear >= steps[code]) ++code;
        return std::uint8_t(code);
    }
};

/// The table, built on first use. The PNG writer reads it inline: through the exported
/// linearToSrgb8, a call and the guard of its static per sample, it cost 2.7 % of a render.
const Srgb8Table& srgb8Table() {
    static const Srgb8Table table;  // about 20,000 pow calls, once
    return table;
}

double decodeSrgb(double encoded) {
    return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

// ---------------------------------------------------------------- libpng, C style
//
// libpng reports errors by longjmp. The functions below that call setjmp hold only plain C
// values, so the jump skips no C++ destructor; the C++ code around them owns the buffers.

struct PngError {
    char message[256] = "unknown libpng error";
};

void onPngError(png_structp png, png_const_charp message) {
    auto* error = static_cast<PngError*>(png_get_error_ptr(png));
    std::snprintf(error->message, sizeof error->message, "%s", message);
    png_longjmp(png, 1);
}

void onPngWarning(png_structp, png_const_charp) {}  // warnings (e.g. odd chunks) are not failures

void writeToStream(png_structp png, png_bytep data, png_size_t size) {
    static_cast<std::ostream*>(png_get_io_ptr(png))->write(reinterpret_cast<const char*>(data), std::streamsize(size));
}
void flushStream(png_structp) {}  // AtomicFile::commit() flushes and checks

/// Writes RGB rows (8 or 16 bits per sample, 16-bit big-endian) with an sRGB chunk to `out`
/// (its errors are checked by the caller).
bool writePngRows(std::ostream* out, png_uint_32 width, png_uint_32 height, int bitDepth, png_bytepp rows,
                  PngError* error) {
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, error, onPngError, onPngWarning);
    if (!png) return false;
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return false;
    }
    png_set_write_fn(png, out, writeToStream, flushStream);
    png_set_IHDR(png, info, width, height, bitDepth, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    // zlib's fast match finder: a 640x480 render compresses 3-4x faster than at the default
    // level 6 (about 20 ms less, one thread, after a render of 0.1 s) for a file about 12% larger.
    png_set_compression_level(png, 2);
    // One row filter, "up", instead of libpng's choice per row among all five, which cost as much
    // as the compression (4 % of a 640x480 render's CPU): files within 1.5 % of the size.
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return true;
}

/// A read in progress; PngReadGuard destroys it on every path.
struct PngRead {
    std::FILE* file = nullptr;
    png_structp png = nullptr;
    png_infop info = nullptr;
    PngError error;
    png_uint_32 width = 0;
    png_uint_32 height = 0;
    int bitDepth = 8;    ///< after the transforms: 8 or 16, RGBA
    bool srgb = true;    ///< false: plain power law with `gamma`
    double gamma = 1.0;  ///< file gamma from gAMA: encoded = linear^gamma
};

/// Reads the header and sets the transforms that turn any PNG into 8- or 16-bit RGBA.
bool readPngHeader(PngRead* read) {
    read->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &read->error, onPngError, onPngWarning);
    if (!read->png) return false;
    read->info = png_create_info_struct(read->png);
    if (!read->info) return false;
    if (setjmp(png_jmpbuf(read->png))) return false;
    png_init_io(read->png, read->file);
    png_read_info(read->png, read->info);
    const int colorType = png_get_color_type(read->png, read->info);
    const int bitDepth = png_get_bit_depth(read->png, read->info);
    if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(read->png);
    if (colorType == PNG_COLOR_TYPE_GRAY && bitDepth < 8) png_set_expand_gray_1_2_4_to_8(read->png);
    if (png_get_valid(read->png, read->info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(read->png);
    if (colorType == PNG_COLOR_TYPE_GRAY || colorType == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(read->png);
    if (!(colorType & PNG_COLOR_MASK_ALPHA) && !png_get_valid(read->png, read->info, PNG_INFO_tRNS))
        png_set_add_alpha(read->png, 0xffff, PNG_FILLER_AFTER);
    png_set_interlace_handling(read->png);
    // Files without colour information are taken to be sRGB, as browsers do.
    int intent = 0;
    double fileGamma = 0.0;
    if (!png_get_sRGB(read->png, read->info, &intent) && png_get_gAMA(read->png, read->info, &fileGamma) &&
        fileGamma > 0.0) {
        read->srgb = false;
        read->gamma = fileGamma;
    }
    png_read_update_info(read->png, read->info);
    read->width = png_get_image_width(read->png, read->info);
    read->height = png_get_image_height(read->png, read->info);
    read->bitDepth = png_get_bit_depth(read->png, read->info);
    return true;
}

bool readPngRows(PngRead* read, png_bytepp rows) {
    if (setjmp(png_jmpbuf(read->png))) return false;
    png_read_image(read->png, rows);
    png_read_end(read->png, nullptr);
    return true;
}

struct PngReadGuard {
    PngRead& read;
    ~PngReadGuard() {
        if (read.png) png_destroy_read_struct(&read.png, read.info ? &read.info : nullptr, nullptr);
        if (read.file) std::fclose(read.file);
    }
};

// ---------------------------------------------------------------- writers

void checkImage(const Image& image, const std::string& path) {
    const std::size_t pixels = static_cast<std::size_t>(std::max(image.width, 0)) * std::max(image.height, 0);
    if (image.width <= 0 || image.height <= 0 || image.rgba.size() != 4 * pixels)
        throw std::runtime_error(
            AtomicFile::failureMessage(path, "the image is empty or its pixel buffer has the wrong size"));
    if (!image.depth.empty() && image.depth.size() != pixels)
        throw std::runtime_error(AtomicFile::failureMessage(path, "the depth buffer has the wrong size"));
    if (!image.normal.empty() && image.normal.size() != 3 * pixels)
        throw std::runtime_error(AtomicFile::failureMessage(path, "the normal buffer has the wrong size"));
}

void writePng(const Image& image, AtomicFile& target, int bitDepth) {
    const std::size_t width = image.width;
    const std::size_t height = image.height;
    const std::size_t bytesPerSample = bitDepth == 16 ? 2 : 1;
    const double scale = bitDepth == 16 ? 65535.0 : 255.0;
    std::vector<png_byte> data(width * height * 3 * bytesPerSample);
    const Srgb8Table& srgb8 = srgb8Table();
    for (std::size_t pixel = 0; pixel < width * height; ++pixel) {
        for (std::size_t channel = 0; channel < 3; ++channel) {
            const float linear = image.rgba[4 * pixel + channel];
            const auto value = bitDepth == 16 ? static_cast<unsigned>(std::lround(encodeSrgb(linear) * scale))
                                              : unsigned(srgb8(linear));
            png_byte* out = &data[(3 * pixel + channel) * bytesPerSample];
            if (bitDepth == 16) {
                out[0] = static_cast<png_byte>(value >> 8);  // PNG stores 16-bit samples big-endian
                out[1] = static_cast<png_byte>(value & 0xff);
            } else {
                out[0] = static_cast<png_byte>(value);
            }
        }
    }
    std::vector<png_bytep> rows(height);
    for (std::size_t row = 0; row < height; ++row) rows[row] = &data[row * width * 3 * bytesPerSample];

    PngError error;
    if (!writePngRows(&target.stream(), static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bitDepth,
                      rows.data(), &error)) {
        target.checkWrites();  // a failed write (a full disk) with its reason
        throw std::runtime_error(AtomicFile::failureMessage(target.path(), error.message));
    }
}

/// OpenEXR's output through AtomicFile's checked stream.
class ExrStream : public Imf::OStream {
public:
    ExrStream(std::ostream& out, const std::string& path) : Imf::OStream(path.c_str()), out_(out) {}
    void write(const char data[], int size) override {
        out_.write(data, size);
        if (!out_) throw std::runtime_error("write failed");  // the reason comes from commit()
    }
    std::uint64_t tellp() override { return std::uint64_t(out_.tellp()); }
    void seekp(std::uint64_t position) override { out_.seekp(std::streamoff(position)); }

private:
    std::ostream& out_;
};

void writeExr(const Image& image, AtomicFile& target) {
    const std::size_t width = image.width;
    const std::size_t height = image.height;
    const std::size_t pixels = width * height;
    // Colours as HALF (ample for display-referred linear light); depth and normals as FLOAT,
    // since compositing (depth of field, relighting) needs their precision.
    // RGB is the surface alone, premultiplied by alpha, so the fractal composites over any
    // plate (an image without a separate surface pass falls back to its full colour).
    const bool haveSurface = image.surface.size() == 3 * pixels;
    std::vector<half> rgba(4 * pixels);
    for (std::size_t pixel = 0; pixel < pixels; ++pixel) {
        for (int channel = 0; channel < 3; ++channel)
            rgba[4 * pixel + channel] =
                half(haveSurface ? image.surface[3 * pixel + channel] : image.rgba[4 * pixel + channel]);
        rgba[4 * pixel + 3] = half(image.rgba[4 * pixel + 3]);
    }
    // Misses have depth +inf in memory; in the file they get 1e10, as Blender writes for its
    // background, because infinities break many compositing nodes.
    std::vector<float> depth(image.depth);
    for (float& value : depth)
        if (!std::isfinite(value)) value = 1e10f;

    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    Imf::FrameBuffer frame;
    const char* colorNames[4] = {"R", "G", "B", "A"};
    for (int channel = 0; channel < 4; ++channel) {
        header.channels().insert(colorNames[channel], Imf::Channel(Imf::HALF));
        frame.insert(colorNames[channel], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(rgba.data() + channel),
                                                     4 * sizeof(half), 4 * sizeof(half) * width));
    }
    if (!depth.empty()) {
        header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
        frame.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(depth.data()), sizeof(float),
                                     sizeof(float) * width));
    }
    if (image.normal.size() == 3 * pixels) {
        const char* normalNames[3] = {"N.X", "N.Y", "N.Z"};
        // OpenEXR only reads from the buffer; the const_cast is its API's, not a write.
        char* base = reinterpret_cast<char*>(const_cast<float*>(image.normal.data()));
        for (int channel = 0; channel < 3; ++channel) {
            header.channels().insert(normalNames[channel], Imf::Channel(Imf::FLOAT));
            frame.insert(normalNames[channel], Imf::Slice(Imf::FLOAT, base + channel * sizeof(float), 3 * sizeof(float),
                                                          3 * sizeof(float) * width));
        }
    }

    try {
        ExrStream stream(target.stream(), target.path());
        Imf::OutputFile file(stream, header);
        file.setFrameBuffer(frame);
        file.writePixels(image.height);
    } catch (const std::exception& error) {
        target.checkWrites();  // throws with the write's reason ("No space left on device")
        throw std::runtime_error(AtomicFile::failureMessage(target.path(), error.what()));
    }
}

}  // namespace


std::uint8_t linearToSrgb8(float linear) { return srgb8Table()(linear); }

void writeImage(const Image& image, AtomicFile& target, ImageFormat format) {
    checkImage(image, target.path());
    switch (format) {
        case ImageFormat::Png8: writePng(image, target, 8); return;
        case ImageFormat::Png16: writePng(image, target, 16); return;
        case ImageFormat::Exr: writeExr(image, target); return;
    }
    throw std::runtime_error(AtomicFile::failureMessage(target.path(), "unknown image format"));
}

void writeImage(const Image& image, const std::string& path, ImageFormat format, Existing existing) {
    checkImage(image, path);  // before the file is opened
    AtomicFile target(path, existing);
    writeImage(image, target, format);
    target.commit();  // reports a failed write (a full disk) with its reason
}

Image readPng(const std::string& path) {
    auto fail = [&](const std::string& reason) {
        return std::runtime_error("cannot read '" + inputExcerpt(path) + "': " + reason);
    };
    PngRead read;
    PngReadGuard guard{read};
    read.file = platform::openFile(path, "rb");
    if (!read.file) throw fail(std::strerror(errno));
    png_byte signature[8] = {};
    if (std::fread(signature, 1, 8, read.file) != 8 || png_sig_cmp(signature, 0, 8) != 0) throw fail("not a PNG file");
    std::rewind(read.file);
    if (!readPngHeader(&read)) throw fail(read.error.message);

    const std::size_t width = read.width;
    const std::size_t height = read.height;
    const std::size_t bytesPerSample = read.bitDepth == 16 ? 2 : 1;
    const std::size_t rowBytes = width * 4 * bytesPerSample;
    if (png_get_rowbytes(read.png, read.info) != rowBytes) throw fail("unsupported PNG layout");
    std::vector<png_byte> data(rowBytes * height);
    std::vector<png_bytep> rows(height);
    for (std::size_t row = 0; row < height; ++row) rows[row] = &data[row * rowBytes];
    if (!readPngRows(&read, rows.data())) throw fail(read.error.message);

    const double maximum = read.bitDepth == 16 ? 65535.0 : 255.0;
    auto toLinear = [&](double encoded) {
        return read.srgb ? decodeSrgb(encoded) : std::pow(encoded, 1.0 / read.gamma);
    };
    // 8-bit files: decode the 256 possible values once.
    std::array<float, 256> table{};
    for (int value = 0; value < 256; ++value) table[value] = static_cast<float>(toLinear(value / 255.0));

    Image image;
    image.width = static_cast<int>(width);
    image.height = static_cast<int>(height);
    image.rgba.resize(width * height * 4);
    for (std::size_t sample = 0; sample < width * height * 4; ++sample) {
        const bool alpha = sample % 4 == 3;  // alpha is linear coverage, never gamma-encoded
        if (bytesPerSample == 2) {
            const unsigned value = (unsigned{data[2 * sample]} << 8) | data[2 * sample + 1];
            image.rgba[sample] = static_cast<float>(alpha ? value / maximum : toLinear(value / maximum));
        } else {
            const unsigned value = data[sample];
            image.rgba[sample] = alpha ? static_cast<float>(value / maximum) : table[value];
        }
    }
    return image;
}

}  // namespace dqj
