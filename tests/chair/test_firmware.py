"""The firmware's portable C core on the host: unit tests (shared vectors, fuzzing, watchdog,
clamps, slew), the same under ASan/UBSan, the virtual chair build, and the Cortex-M4
cross-compile with its flash/RAM figures."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from autohaptics.chair.simulate import build_simulator
from autohaptics.errors import DeviceError
from shared_data import REPO

pytestmark = pytest.mark.firmware

FIRMWARE = REPO / "firmware"


def _need(tool: str, package: str) -> str:
    path = shutil.which(tool)
    if path is None:
        pytest.fail(f"{tool} not found on PATH: install it with `apt-get install {package}`")
    return path


@pytest.fixture(scope="module")
def build_dir(tmp_path_factory) -> Path:
    _need("make", "make")
    _need(os.environ.get("CC", "cc"), "gcc")
    return tmp_path_factory.mktemp("firmware-build")


def _make(build_dir: Path, *targets: str) -> subprocess.CompletedProcess:
    return subprocess.run(["make", "-C", str(FIRMWARE), f"BUILD={build_dir}", *targets],
                          capture_output=True, text=True, timeout=300)


def _sanitizers_work(tmp_path: Path) -> bool:
    src = tmp_path / "probe.c"
    src.write_text("int main(void) { return 0; }\n")
    cc = os.environ.get("CC", "cc")
    proc = subprocess.run([cc, "-fsanitize=address,undefined", str(src), "-o", str(tmp_path / "probe")],
                          capture_output=True, text=True)
    return proc.returncode == 0 and subprocess.run([str(tmp_path / "probe")]).returncode == 0


def test_core_host_unit_tests(build_dir):
    proc = _make(build_dir, "test")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert re.search(r"^\d+ checks, 0 failed$", proc.stdout, re.M), proc.stdout
    assert "vectors: 25 frame vectors" in proc.stdout
    assert "fuzz corrupted:" in proc.stdout and "fuzz random:" in proc.stdout


def test_core_under_address_and_undefined_sanitizers(build_dir, tmp_path):
    if not _sanitizers_work(tmp_path):
        pytest.skip("this C compiler cannot build and run -fsanitize=address,undefined programs")
    proc = _make(build_dir, "test-asan")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert re.search(r"^\d+ checks, 0 failed$", proc.stdout, re.M), proc.stdout
    assert "ERROR: AddressSanitizer" not in proc.stderr and "runtime error" not in proc.stderr


def test_virtual_chair_builds_with_make_and_from_python(build_dir, tmp_path):
    proc = _make(build_dir, "sim")
    assert proc.returncode == 0, proc.stderr
    assert os.access(build_dir / "autohaptics-chair-sim", os.X_OK)
    binary = build_simulator(build_dir=tmp_path)
    assert binary.parent == tmp_path and os.access(binary, os.X_OK)
    mtime = binary.stat().st_mtime_ns
    assert build_simulator(build_dir=tmp_path) == binary  # cached per source version
    assert binary.stat().st_mtime_ns == mtime


def test_missing_compiler_is_a_clear_error(tmp_path):
    with pytest.raises(DeviceError, match="no C compiler 'no-such-cc'"):
        build_simulator(build_dir=tmp_path, cc="no-such-cc")


def test_cross_compile_for_cortex_m4_reports_flash_and_ram(build_dir, capsys):
    if shutil.which("arm-none-eabi-gcc") is None:
        pytest.skip("arm-none-eabi-gcc not found (apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi)")
    proc = _make(build_dir, "size")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    total = re.search(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+\(TOTALS\)", proc.stdout, re.M)
    image = re.search(r"^\s*(\d+)\s+(\d+)\s+(\d+)\s+\d+\s+[0-9a-f]+\s+\S*size_main\.elf", proc.stdout, re.M)
    chair = re.search(r"^[0-9a-f]+ ([0-9a-f]+) b chair$", proc.stdout, re.M)
    assert total and image and chair, proc.stdout
    core_text, core_data, core_bss = map(int, total.groups())
    img_text, img_data, img_bss = map(int, image.groups())
    chair_ram = int(chair.group(1), 16)
    with capsys.disabled():
        print(f"\n[firmware size] Cortex-M4 -Os: core flash {core_text + core_data} B "
              f"(text {core_text}, data {core_data}, bss {core_bss}); chair_t state {chair_ram} B RAM; "
              f"minimal linked image: text {img_text}, data {img_data}, bss {img_bss}")
    # Budgets for a Teensy 3.2 (256 KiB flash, 64 KiB RAM): the core must stay a small fraction.
    assert 0 < core_text <= 8 * 1024
    assert core_data == 0 and core_bss == 0  # all state lives in the caller's chair_t: no hidden globals
    assert chair_ram <= 1024
