// The gateway's own object dictionary: the communication objects of CiA 301
// 7.5 that a CANopen device acting as NMT master and SDO server needs, with
// the value rules the standard gives for each (see the .cpp for sections).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <system_error>

#include "canopen/od/object_dictionary.hpp"

namespace canopen::od {

struct GatewayIdentity {
  std::uint32_t device_type = 0x00000000;  // 1000h: no standard device profile (7.5.2.1)
  std::uint32_t vendor_id = 0;             // 1018h sub 1
  std::uint32_t product_code = 0;          // 1018h sub 2
  std::uint32_t revision = 0;              // 1018h sub 3
  std::uint32_t serial = 0;                // 1018h sub 4
  std::string device_name = "canopen-gateway";  // 1008h
  std::string hardware_version = "linux";       // 1009h
  std::string software_version;                 // 100Ah
};

struct GatewayDictionaryOptions {
  std::uint8_t error_history_size = 8;        // 1003h entries
  std::uint8_t heartbeat_consumers = 8;       // 1016h entries
  std::uint8_t sdo_clients = 127;             // 1280h.. one client channel per possible node
  std::uint8_t rpdos = 4, tpdos = 4;          // 1400h/1600h, 1800h/1A00h
  // Called when "save" is written to 1010h sub N / "load" to 1011h sub N
  // (1 all, 2 communication, 3 application parameters). Returning an error
  // aborts the download with it (the standard suggests 0606 0000h when the
  // storage fails). Unset: the signature is accepted and nothing is stored.
  // (The "= nullptr" spares callers that list only the fields above a
  // -Wmissing-field-initializers warning.)
  std::function<std::error_code(std::uint8_t sub)> on_store = nullptr;
  std::function<std::error_code(std::uint8_t sub)> on_restore = nullptr;
};

// The store/restore behaviour of 7.5.2.13/7.5.2.14 on the 1010h and 1011h
// a dictionary already has (either may be absent): reading sub N (N >= 1)
// answers 1 (stores on command only); writing "save" (65766173h) to 1010h
// sub N calls on_store(N), "load" (64616F6Ch) to 1011h sub N on_restore(N),
// whose error aborts the download; any other value aborts 08000020h. The
// gateway's own dictionary uses it, and so do the simulated devices.
void install_store_restore(ObjectDictionary& od, std::function<std::error_code(std::uint8_t sub)> on_store,
                           std::function<std::error_code(std::uint8_t sub)> on_restore);

// Builds the dictionary for `node_id` (1..127): 1000h, 1001h, 1003h, 1005h,
// 1006h, 1007h, 1008h-100Ah, 100Ch, 100Dh, 1010h, 1011h, 1012h-1019h, 1200h,
// 1280h..., 1400h/1600h, 1800h/1A00h, with hooks enforcing the value rules.
ObjectDictionary make_gateway_dictionary(std::uint8_t node_id, const GatewayIdentity& identity,
                                         const GatewayDictionaryOptions& options = {});

// Records an error in 1003h (7.5.2.4): the newest at sub 1, older ones move
// down one sub-index, the oldest falls off when the history is full; sub 0
// counts the entries. No-op when the dictionary has no 1003h.
void push_error_history(ObjectDictionary& od, std::uint32_t error_field);

}  // namespace canopen::od
