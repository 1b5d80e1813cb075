#!/usr/bin/env bash
# Cross-builds the pen firmware for the STM32F103VE and checks its flash and RAM use.
#
# Expects (CI installs them before calling this script):
#   rustup target add thumbv7m-none-eabi
#   apt-get install -y binutils-arm-none-eabi      (for arm-none-eabi-size)
# Fails if flash (text+data) or static RAM (data+bss) exceeds half of the chip's 512 KiB flash / 64 KiB RAM.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")"

TARGET=thumbv7m-none-eabi
FLASH_TOTAL=$((512 * 1024))
RAM_TOTAL=$((64 * 1024))

if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
    echo "error: Rust target $TARGET is not installed (rustup target add $TARGET)" >&2
    exit 1
fi
SIZE_TOOL=""
for tool in arm-none-eabi-size size; do
    if command -v "$tool" >/dev/null 2>&1; then
        SIZE_TOOL="$tool"
        break
    fi
done
if [ "$SIZE_TOOL" != "arm-none-eabi-size" ]; then
    echo "error: arm-none-eabi-size not found (apt-get install -y binutils-arm-none-eabi)" >&2
    exit 1
fi

cargo build --release --locked

ELF="target/$TARGET/release/fires-pen-app"
echo "== $SIZE_TOOL $ELF"
"$SIZE_TOOL" "$ELF"
# Berkeley format: text data bss dec hex filename
read -r TEXT DATA BSS _ < <("$SIZE_TOOL" "$ELF" | awk 'NR == 2 { print $1, $2, $3 }')
FLASH=$((TEXT + DATA))
RAM=$((DATA + BSS))
pct() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", 100 * a / b }'; }
echo "firmware flash: $FLASH bytes of $FLASH_TOTAL ($(pct "$FLASH" "$FLASH_TOTAL") %)"
echo "firmware RAM (static, data+bss): $RAM bytes of $RAM_TOTAL ($(pct "$RAM" "$RAM_TOTAL") %)"

status=0
if [ "$FLASH" -gt $((FLASH_TOTAL / 2)) ]; then
    echo "error: flash use exceeds half of the STM32F103VE's flash" >&2
    status=1
fi
if [ "$RAM" -gt $((RAM_TOTAL / 2)) ]; then
    echo "error: RAM use exceeds half of the STM32F103VE's RAM" >&2
    status=1
fi
exit $status
