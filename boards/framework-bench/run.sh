#!/usr/bin/env bash
# Builds the benches and the minimal firmwares (minimal/) and prints every
# figure: per-sample framework overhead in instructions under QEMU, SPI cost, flash/RAM.
# Idempotent: only builds into ./bench/target and ./minimal/*/target.
set -euo pipefail
cd "$(dirname "$0")"

QEMU=(qemu-system-arm -machine netduinoplus2 -nographic -monitor none -serial none
      -icount shift=0 -semihosting-config enable=on,target=native)
ELF_DIR=bench/target/thumbv7em-none-eabihf/release
LLVM_BIN="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
LLVM_SIZE="$LLVM_BIN/llvm-size"; [ -x "$LLVM_SIZE" ] || LLVM_SIZE=llvm-size

echo "== build benches (release: opt-level s, lto, codegen-units 1)"
(cd bench && cargo build --release --quiet)

for elf in rtic-bench embassy-model embassy-exti-regs spi-bench; do
    echo "== qemu: $elf"
    timeout 120 "${QEMU[@]}" -kernel "$ELF_DIR/$elf"
done

echo "== build minimal firmwares (minimal/rtic, minimal/emb)"
(cd minimal/rtic && cargo build --release --quiet)
(cd minimal/emb && cargo build --release --quiet)

size_line() { # name elf
    "$LLVM_SIZE" -A "$2" | awk -v name="$1" '
        { s[$1] = $2 }
        END { printf "%s: flash_bytes=%d (.vector_table %d + .text %d + .rodata %d + .data %d) ram_bytes=%d (.data %d + .bss %d; plus .uninit %d, mostly the 1 KiB defmt-rtt buffer)\n",
              name, s[".vector_table"] + s[".text"] + s[".rodata"] + s[".data"],
              s[".vector_table"], s[".text"], s[".rodata"], s[".data"],
              s[".data"] + s[".bss"], s[".data"], s[".bss"], s[".uninit"] }'
}
echo "== llvm-size -A (minimal firmwares)"
size_line "rtic minimal (RTIC 2.4.0 + stm32f4xx-hal 0.23.0)" minimal/rtic/target/thumbv7em-none-eabihf/release/rtic-app
size_line "embassy minimal (embassy-stm32 0.6.0 + embassy-executor 0.10.0)" minimal/emb/target/thumbv7em-none-eabihf/release/emb
