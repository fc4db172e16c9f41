// Whole-buffer gzip (zlib inflate) and xz (liblzma) decoding with a hard cap on the output size.
#include "io/decompress.h"

#include <lzma.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>

#include "common/error.h"

namespace pms {

namespace {

// Input is fed in slices: zlib counts in 32-bit units, and each slice is a natural progress tick.
constexpr size_t kInputSlice = size_t(1) << 20;
// The dictionary of an xz stream is allocated up front from its header; xz -9 needs 64 MiB, so a
// header asking for more than this is hostile or exotic.
constexpr uint64_t kXzMemoryLimit = uint64_t(1) << 30;

bool ends_with_nocase(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() &&
         std::equal(suffix.begin(), suffix.end(), s.end() - suffix.size(),
                    [](char a, char b) { return std::tolower(uint8_t(a)) == std::tolower(uint8_t(b)); });
}

// Growable output that refuses to grow past the cap; the decoders write straight into it.
class Output {
 public:
  Output(const std::string& name, size_t input_size, uint64_t limit) : name_(name), limit_(limit) {
    // Meshes compress 3-8x; start near that so a typical file needs at most one or two regrowths.
    bytes_.resize(size_t(std::min<uint64_t>(limit_ + 1, std::max<uint64_t>(uint64_t(input_size) * 4, 1 << 16))));
  }

  uint8_t* cursor() { return bytes_.data() + used_; }
  size_t space() const { return bytes_.size() - used_; }
  void advance(size_t produced) {
    used_ += produced;
    if (used_ > limit_)
      fail(name_,
           "decompresses to more than " + std::to_string(limit_) + " bytes (refusing a possible decompression bomb)");
  }

  // Room for one byte past the limit: a stream of exactly `limit` bytes may need another call to
  // report its end, and a byte that lands there proves the output is too large.
  void grow() { bytes_.resize(size_t(std::min<uint64_t>(limit_ + 1, uint64_t(bytes_.size()) * 2))); }

  std::vector<uint8_t> take() {
    bytes_.resize(used_);
    return std::move(bytes_);
  }

 private:
  const std::string& name_;
  uint64_t limit_;
  std::vector<uint8_t> bytes_;
  size_t used_ = 0;
};

std::vector<uint8_t> gunzip(const std::string& name, std::span<const uint8_t> in, const ProgressFn& progress,
                            uint64_t max_output) {
  z_stream zs{};
  if (inflateInit2(&zs, 16 + MAX_WBITS) != Z_OK) fail(name, "cannot initialise zlib");
  struct End {
    z_stream* zs;
    ~End() { inflateEnd(zs); }
  } end{&zs};

  Output out(name, in.size(), max_output);
  size_t fed = 0;
  for (;;) {
    if (zs.avail_in == 0 && fed < in.size()) {
      const size_t n = std::min(kInputSlice, in.size() - fed);
      zs.next_in = const_cast<Bytef*>(in.data() + fed);  // zlib's API is not const-correct
      zs.avail_in = uInt(n);
      fed += n;
      report(progress, "load", double(fed - n) / double(in.size()));
    }
    if (out.space() == 0) out.grow();
    const size_t space = std::min(out.space(), kInputSlice * 64);
    zs.next_out = out.cursor();
    zs.avail_out = uInt(space);
    const int ret = inflate(&zs, Z_NO_FLUSH);
    out.advance(space - zs.avail_out);
    if (ret == Z_STREAM_END) {
      const size_t consumed = fed - zs.avail_in;
      if (consumed == in.size()) break;
      // gzip allows several members back to back (cat a.gz b.gz); anything else is junk.
      if (in.size() - consumed < 2 || in[consumed] != 0x1f || in[consumed + 1] != 0x8b)
        fail(name, "unexpected data after the end of the gzip stream");
      inflateReset(&zs);
      continue;
    }
    if (ret == Z_BUF_ERROR && zs.avail_in == 0 && fed == in.size()) fail(name, "truncated gzip data");
    if (ret != Z_OK && ret != Z_BUF_ERROR)
      fail(name, std::string("corrupt gzip data (") + (zs.msg ? zs.msg : "zlib error " + std::to_string(ret)) + ")");
  }
  report(progress, "load", 1.0);
  return out.take();
}

const char* lzma_problem(lzma_ret ret) {
  switch (ret) {
    case LZMA_FORMAT_ERROR:
      return "not xz data (bad magic)";
    case LZMA_OPTIONS_ERROR:
      return "unsupported xz options";
    case LZMA_DATA_ERROR:
      return "corrupt xz data";
    case LZMA_BUF_ERROR:
      return "truncated xz data";
    case LZMA_MEMLIMIT_ERROR:
      return "xz stream needs a dictionary larger than 1 GiB";
    case LZMA_MEM_ERROR:
      return "out of memory while decompressing xz data";
    default:
      return "xz decoder error";
  }
}

std::vector<uint8_t> unxz(const std::string& name, std::span<const uint8_t> in, const ProgressFn& progress,
                          uint64_t max_output) {
  lzma_stream strm = LZMA_STREAM_INIT;
  // LZMA_CONCATENATED: like xz(1), accept several streams and stream padding.
  if (lzma_stream_decoder(&strm, kXzMemoryLimit, LZMA_CONCATENATED) != LZMA_OK) fail(name, "cannot initialise liblzma");
  struct End {
    lzma_stream* strm;
    ~End() { lzma_end(strm); }
  } end{&strm};

  Output out(name, in.size(), max_output);
  size_t fed = 0;
  for (;;) {
    if (strm.avail_in == 0 && fed < in.size()) {
      const size_t n = std::min(kInputSlice, in.size() - fed);
      strm.next_in = in.data() + fed;
      strm.avail_in = n;
      fed += n;
      report(progress, "load", double(fed - n) / double(in.size()));
    }
    if (out.space() == 0) out.grow();
    strm.next_out = out.cursor();
    strm.avail_out = out.space();
    const size_t space = out.space();
    const lzma_ret ret = lzma_code(&strm, fed == in.size() ? LZMA_FINISH : LZMA_RUN);
    out.advance(space - strm.avail_out);
    if (ret == LZMA_STREAM_END) break;
    if (ret != LZMA_OK) fail(name, lzma_problem(ret));
  }
  report(progress, "load", 1.0);
  return out.take();
}

}  // namespace

Compression compression_of(std::string_view name) {
  if (ends_with_nocase(name, ".gz")) return Compression::gzip;
  if (ends_with_nocase(name, ".xz")) return Compression::xz;
  return Compression::none;
}

std::string_view strip_compression_suffix(std::string_view name) {
  return compression_of(name) == Compression::none ? name : name.substr(0, name.size() - 3);
}

std::vector<uint8_t> decompress(const std::string& name, Compression codec, std::span<const uint8_t> bytes,
                                const ProgressFn& progress, uint64_t max_output) {
  switch (codec) {
    case Compression::gzip:
      return gunzip(name, bytes, progress, max_output);
    case Compression::xz:
      return unxz(name, bytes, progress, max_output);
    case Compression::none:
      break;
  }
  return {bytes.begin(), bytes.end()};
}

}  // namespace pms
