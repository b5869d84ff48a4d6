// The compact sample encoding's zstd framing (sample_codec_framing_internal.hpp). No floating
// point here.

#include <zstd.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "hattr/core/error.hpp"
#include "sample_codec_framing_internal.hpp"

namespace hattr::io::detail {
namespace {

/// zstd's contexts, one of each per thread, kept for the thread's life.
ZSTD_CCtx* compressionContext() {
  thread_local const std::unique_ptr<ZSTD_CCtx, decltype(&ZSTD_freeCCtx)> context(ZSTD_createCCtx(), &ZSTD_freeCCtx);
  HATTR_THROW_UNLESS(context != nullptr, "sample encoding: zstd: out of memory");
  return context.get();
}

/// The decompression context, as compressionContext.
ZSTD_DCtx* decompressionContext() {
  thread_local const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> context(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  HATTR_THROW_UNLESS(context != nullptr, "samples: zstd: out of memory");
  return context.get();
}

/// One whole zstd frame (RFC 8878) that declares `content_size` bytes, with its content's
/// checksum, and small enough to hold them: checked before anything is allocated.
void checkFrame(std::string_view frame, std::uint64_t content_size) {
  HATTR_THROW_UNLESS(ZSTD_getFrameContentSize(frame.data(), frame.size()) == content_size,
                     "samples: the compressed residuals are not one zstd frame of {} bytes", content_size);
  const std::size_t whole = ZSTD_findFrameCompressedSize(frame.data(), frame.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(whole) && whole == frame.size(),
                     "samples: the compressed residuals are not exactly one zstd frame ({} bytes stored)", frame.size());
  // The frame header descriptor follows the 4-byte magic number; bit 2 says a checksum ends it.
  HATTR_THROW_UNLESS(frame.size() > 4 && (static_cast<unsigned char>(frame[4]) & 0x04) != 0,
                     "samples: the compressed residuals carry no checksum");
  // A zstd block of at most 128 KiB takes at least 4 bytes (an RLE block): no more content fits.
  HATTR_THROW_UNLESS(content_size <= (frame.size() / 4 + 1) * 131072,
                     "samples: {} bytes of compressed residuals cannot hold {} bytes", frame.size(), content_size);
}

}  // namespace

/// `content` as one zstd frame with its checksum, each part (ending at `ends`) flushed into
/// zstd blocks of its own.
std::string compressInParts(std::string_view content, std::span<const std::size_t> ends, int level) {
  ZSTD_CCtx* context = compressionContext();
  ZSTD_CCtx_reset(context, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(context, ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(context, ZSTD_c_checksumFlag, 1);
  const std::size_t pledged = ZSTD_CCtx_setPledgedSrcSize(context, content.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(pledged), "sample encoding: zstd: {}", ZSTD_getErrorName(pledged));
  std::string frame(ZSTD_compressBound(content.size()) + 64 * ends.size(), '\0');
  ZSTD_outBuffer out{frame.data(), frame.size(), 0};
  std::size_t from = 0;
  for (std::size_t e = 0; e < ends.size(); ++e) {
    ZSTD_inBuffer in{content.data() + from, ends[e] - from, 0};
    const ZSTD_EndDirective mode = e + 1 == ends.size() ? ZSTD_e_end : ZSTD_e_flush;
    for (;;) {
      const std::size_t left = ZSTD_compressStream2(context, &out, &in, mode);
      HATTR_THROW_UNLESS(!ZSTD_isError(left), "sample encoding: zstd: {}", ZSTD_getErrorName(left));
      HATTR_DEMAND(left == 0 || out.pos < out.size, "zstd's output buffer was sized by ZSTD_compressBound");
      if (left == 0 && in.pos == in.size) break;
    }
    from = ends[e];
  }
  frame.resize(out.pos);
  return frame;
}

/// The frame's content, decompressed and checked against the header outside it (which must be
/// its first `header_bytes` bytes).
std::unique_ptr<char[]> decompressContent(std::string_view blob, std::size_t header_bytes, std::uint64_t content_size) {
  const std::string_view frame = blob.substr(header_bytes + 8);
  checkFrame(frame, content_size);
  auto content = std::make_unique_for_overwrite<char[]>(content_size);
  const std::size_t got = ZSTD_decompressDCtx(decompressionContext(), content.get(), content_size, frame.data(), frame.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(got) && got == content_size, "samples: the compressed residuals are damaged: {}",
                     ZSTD_isError(got) ? ZSTD_getErrorName(got) : "short");
  HATTR_THROW_UNLESS(std::memcmp(content.get(), blob.data(), header_bytes) == 0,
                     "samples: the encoded block's header is damaged (it differs from its checksummed copy)");
  return content;
}

}  // namespace hattr::io::detail
