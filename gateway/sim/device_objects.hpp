// What the simulated devices do with the CiA 302-3 program download
// objects of their dictionary. Sans-I/O: the
// functions install hooks on a dictionary; they keep no state of their own
// (the program and its state live in the dictionary's entries), so a copy
// of the dictionary carries them and the hooks stay valid for the
// dictionary's life.
//
// Store/restore (1010h/1011h) are od::install_store_restore() (the
// gateway's own node uses it too); the simulator wires it to the Device.
//
// Program download (CiA 302-3), for each sub-index n present in 1F51h:
//   - 1F50h sub n (DOMAIN): the program image, kept in the dictionary entry,
//     at most kMaxProgramSize bytes (05040005h out of memory beyond); a
//     download while the program runs aborts 08000022h (present device
//     state);
//   - 1F51h sub n (UNSIGNED8) program control: write 0 stop, 1 start,
//     2 reset (restart), 3 clear (the image is erased; refused 08000022h
//     while the program runs); start/reset without an image abort
//     08000022h; other values 06090030h (invalid value). Reading gives the
//     state: 0 stopped, 1 running, 3 no program (empty image);
//   - 1F56h sub n (UNSIGNED32) program software identification: the CRC-32
//     (IEEE 802.3, as zlib and Boost's crc_32_type compute it) of the image,
//     0 when there is none;
//   - 1F57h sub n (UNSIGNED32) flash status identification: 0, "no error"
//     (the image is accepted at once; there is no flash to program).
// The program objects are not parameters: resets and 1011h "load" leave
// them alone (canopen::Device excludes 1F50h-1F5Fh).
//
// Thread safety: none; as the dictionary's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <system_error>

#include "canopen/od/object_dictionary.hpp"

namespace canopen::sim {

inline constexpr std::size_t kMaxProgramSize = std::size_t{4} << 20;

// The simulated devices' 1F56h: CRC-32 of the image (0 for none).
std::uint32_t program_identification(std::span<const std::uint8_t> image);

// Installs the program download behaviour when od has 1F51h (1F50h, 1F56h
// and 1F57h as far as present). Returns false when od has no 1F51h.
bool install_program_objects(od::ObjectDictionary& od);

}  // namespace canopen::sim
