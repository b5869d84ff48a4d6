#pragma once
// The compact sample encoding's zstd framing (sample_codec_framing.cpp): the content (a copy of
// the block's header, then the residuals) as one zstd frame with its checksum, and back.
// Sizes in bytes.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

namespace hattr::io::detail {

/// `content` as one zstd frame with its checksum, each part (ending at `ends`) flushed into
/// zstd blocks of its own. `level` is zstd's. The calling thread keeps its zstd context (and
/// its tables) from one call to the next.
std::string compressInParts(std::string_view content, std::span<const std::size_t> ends, int level);

/// The frame's content, decompressed and checked against the header outside it (which must be
/// its first `header_bytes` bytes). The frame follows the header and the u64 content size in
/// `blob`. Throws InputError for a frame that is not one, is damaged or disagrees with the header.
std::unique_ptr<char[]> decompressContent(std::string_view blob, std::size_t header_bytes, std::uint64_t content_size);

}  // namespace hattr::io::detail
