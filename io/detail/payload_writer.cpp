#include "payload_writer.hpp"

#include <corrlap/io/detail/volume_stream.hpp>
#include <limits>
#include <vector>

#ifdef CORRLAP_HAVE_ZLIB
#include <zlib.h>
#endif

namespace corrlap::io_detail {

#ifdef CORRLAP_HAVE_ZLIB
struct PayloadWriter::Deflater {
  z_stream zs{};
  std::vector<unsigned char> buffer = std::vector<unsigned char>(kChunk);
  ~Deflater() { deflateEnd(&zs); }
};
#else
struct PayloadWriter::Deflater {};
#endif

PayloadWriter::PayloadWriter(std::FILE* file, const std::string& path, Encoding encoding) : file_(file), path_(path) {
  if (encoding == Encoding::Raw) return;
#ifdef CORRLAP_HAVE_ZLIB
  auto d = std::make_unique<Deflater>();
  // 15: a zlib stream; 15 + 16: the same deflate data in a gzip wrapper.
  const int window = encoding == Encoding::Gzip ? 15 + 16 : 15;
  if (deflateInit2(&d->zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, window, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    fail(path, "zlib initialisation failed");
  deflater_ = std::move(d);
#else
  fail(path, "compressed writing needs corrlap built with zlib (zlib1g-dev)");
#endif
}

PayloadWriter::~PayloadWriter() = default;

void PayloadWriter::write(const void* data, std::size_t n) {
  if (!deflater_) {
    // A short write sets the stream's error flag, which OutputFile::commit() reports.
    if (n > 0) (void)std::fwrite(data, 1, n, file_);
    written_ += n;
    return;
  }
#ifdef CORRLAP_HAVE_ZLIB
  auto* bytes = static_cast<const unsigned char*>(data);
  while (n > 0) {
    const std::size_t k = std::min<std::size_t>(n, std::numeric_limits<uInt>::max());
    deflater_->zs.next_in = const_cast<Bytef*>(bytes);
    deflater_->zs.avail_in = uInt(k);
    do {
      deflater_->zs.next_out = deflater_->buffer.data();
      deflater_->zs.avail_out = uInt(deflater_->buffer.size());
      if (deflate(&deflater_->zs, Z_NO_FLUSH) == Z_STREAM_ERROR) fail(path_, "zlib compression failed");
      emit();
    } while (deflater_->zs.avail_out == 0);
    bytes += k;
    n -= k;
  }
#endif
}

void PayloadWriter::emit() {
#ifdef CORRLAP_HAVE_ZLIB
  const std::size_t k = deflater_->buffer.size() - deflater_->zs.avail_out;
  // A short write sets the stream's error flag, which OutputFile::commit() reports.
  (void)std::fwrite(deflater_->buffer.data(), 1, k, file_);
  written_ += k;
#endif
}

void PayloadWriter::finish() {
  if (!deflater_) return;
#ifdef CORRLAP_HAVE_ZLIB
  int rc = Z_OK;
  do {
    deflater_->zs.next_out = deflater_->buffer.data();
    deflater_->zs.avail_out = uInt(deflater_->buffer.size());
    rc = deflate(&deflater_->zs, Z_FINISH);
    if (rc == Z_STREAM_ERROR) fail(path_, "zlib compression failed");
    emit();
  } while (rc != Z_STREAM_END);
#endif
}

}  // namespace corrlap::io_detail
