// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78), as iSCSI, ext4 and LevelDB use it.
// Debian 12 packages no C/C++ crc32c library (only a Python one), hence these few lines.
#pragma once

#include <cstdint>
#include <span>

namespace pointdag {

uint32_t Crc32c(std::span<const uint8_t> data, uint32_t crc = 0);

}  // namespace pointdag
