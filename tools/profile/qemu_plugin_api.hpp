// The part of QEMU's TCG plugin interface (API version 1, QEMU 7.2: Debian 12's qemu-user) that
// the stage counter uses, declared from QEMU's documentation ("QEMU TCG Plugins"): Debian ships
// the plugin-capable emulator but not its header. The emulator resolves these functions in
// itself when it loads the plugin; the plugin exports qemu_plugin_version and
// qemu_plugin_install.
#pragma once

#include <cstddef>
#include <cstdint>

extern "C" {

using qemu_plugin_id_t = std::uint64_t;  // NOLINT(readability-identifier-naming): QEMU's name

// Only passed through: the plugin reads nothing of it.
struct qemu_info_t;       // NOLINT(readability-identifier-naming)
struct qemu_plugin_tb;    // NOLINT(readability-identifier-naming)
struct qemu_plugin_insn;  // NOLINT(readability-identifier-naming)

enum qemu_plugin_cb_flags {  // NOLINT(readability-identifier-naming)
  QEMU_PLUGIN_CB_NO_REGS,    // NOLINT(readability-identifier-naming)
  QEMU_PLUGIN_CB_R_REGS,     // NOLINT(readability-identifier-naming)
  QEMU_PLUGIN_CB_RW_REGS,    // NOLINT(readability-identifier-naming)
};

using qemu_plugin_udata_cb_t = void (*)(qemu_plugin_id_t id, void* userdata);           // NOLINT
using qemu_plugin_vcpu_udata_cb_t = void (*)(unsigned int vcpu_index, void* userdata);  // NOLINT
using qemu_plugin_vcpu_tb_trans_cb_t = void (*)(qemu_plugin_id_t id,                    // NOLINT
                                                qemu_plugin_tb* tb);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id,  // NOLINT
                                           qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_vcpu_tb_exec_cb(qemu_plugin_tb* tb,  // NOLINT
                                          qemu_plugin_vcpu_udata_cb_t cb,
                                          qemu_plugin_cb_flags flags, void* userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id,  // NOLINT
                                    qemu_plugin_udata_cb_t cb, void* userdata);
std::size_t qemu_plugin_tb_n_insns(const qemu_plugin_tb* tb);                          // NOLINT
qemu_plugin_insn* qemu_plugin_tb_get_insn(const qemu_plugin_tb* tb, std::size_t idx);  // NOLINT
const char* qemu_plugin_insn_symbol(const qemu_plugin_insn* insn);                     // NOLINT
void qemu_plugin_outs(const char* string);                                             // NOLINT

}  // extern "C"
