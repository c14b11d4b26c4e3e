"""The FMUs' macOS binaries, checked as far as a Linux machine can: they are built here but cannot
be run. The FMUs are HaselPlatform (FMI 2.0 and 3.0), the slow model's HaselPlatformReduced (FMI 2.0
and 3.0) and HaselInverse (FMI 2.0). With LLVM's tools (llvm-16): FMI 2.0's darwin64 library is
universal, an x86_64 and an arm64 slice; FMI 3.0's x86_64-darwin and aarch64-darwin are one
architecture each. Every slice is a dylib that exports exactly the FMI functions of its version,
depends on /usr/lib/libSystem.B.dylib alone, names its minimum macOS (10.12 on x86_64, 11.0 on
arm64: Rust's minimums for the targets), and the arm64 one carries a code signature (macOS refuses
unsigned arm64 code) whose page hashes match the file, checked here by reading the signature's
CodeDirectory. The hasel command for macOS, one executable each architecture, is checked the same
way but for the exports.

The macOS builds come from `bash ci/test.sh` (profile cross-test; the command for arm64 only, as its
CROSS_CLI_TARGETS say) and `bash ci/platforms.sh` (release), which both run these tests with
HASEL_PLATFORMS=required; run alone on a Linux-only build, they skip, saying so.
"""
import hashlib
import os
import pathlib
import re
import struct
import subprocess
import zipfile

import pytest
from conftest import cross_built, platform_missing
from test_binary import exported_functions

LLVM = pathlib.Path("/usr/lib/llvm-16/bin")
MINIMUM = {"x86_64": "10.12", "arm64": "11.0"}


def llvm(tool, *args):
    path = LLVM / tool
    if not path.exists():
        platform_missing(f"{path} is missing: `bash ci/platforms.sh` installs it (llvm-16)")
    return subprocess.run([str(path), *map(str, args)], capture_output=True, text=True, check=True).stdout


def member(fmu, folder, tmp_path_factory):
    with zipfile.ZipFile(fmu) as z:
        name = next((n for n in z.namelist() if n.startswith(f"binaries/{folder}/")), None)
        if name is None:
            platform_missing(f"{fmu} has no binaries/{folder}/: `bash ci/platforms.sh` builds it")
        assert name.endswith(".dylib"), name
        return pathlib.Path(z.extract(name, tmp_path_factory.mktemp("dylib")))


# (FMU, folder, architectures, what it exports)
LIBRARIES = {
    "HaselPlatform 2.0 darwin64": ("fmu_path", "darwin64", ["x86_64", "arm64"]),
    "HaselInverse 2.0 darwin64": ("inverse_fmu_path", "darwin64", ["x86_64", "arm64"]),
    "HaselPlatform 3.0 x86_64-darwin": ("fmu3_path", "x86_64-darwin", ["x86_64"]),
    "HaselPlatform 3.0 aarch64-darwin": ("fmu3_path", "aarch64-darwin", ["arm64"]),
    "HaselPlatformReduced 2.0 darwin64": ("reduced_fmu_path", "darwin64", ["x86_64", "arm64"]),
    "HaselPlatformReduced 3.0 x86_64-darwin": ("reduced_fmu3_path", "x86_64-darwin", ["x86_64"]),
    "HaselPlatformReduced 3.0 aarch64-darwin": ("reduced_fmu3_path", "aarch64-darwin", ["arm64"]),
}


@pytest.fixture(scope="module", params=list(LIBRARIES))
def library(request, tmp_path_factory):
    fixture, folder, arches = LIBRARIES[request.param]
    return member(request.getfixturevalue(fixture), folder, tmp_path_factory), arches, \
        exported_functions(request.param)


def test_architectures(library):
    path, arches, _ = library
    assert llvm("llvm-lipo", "-archs", path).split() == arches


def slices(library, tmp_path):
    """Each architecture's thin file (llvm-lipo -thin of a universal one)."""
    path, arches, _ = library
    if len(arches) == 1:
        return {arches[0]: path}
    out = {}
    for arch in arches:
        out[arch] = tmp_path / f"{arch}.dylib"
        llvm("llvm-lipo", path, "-thin", arch, "-output", out[arch])
    return out


def test_exports_exactly_the_fmi_functions(library, tmp_path):
    expected = library[2]
    for arch, path in slices(library, tmp_path).items():
        lines = llvm("llvm-nm", "--extern-only", "--defined-only", path).splitlines()
        exported = {line.split()[-1] for line in lines}
        assert exported == {"_" + f for f in expected}, (arch, exported ^ {"_" + f for f in expected})


def load_commands(path):
    """(cmd, fields) of each load command, from llvm-objdump --macho --private-headers."""
    text = llvm("llvm-objdump", "--macho", "--private-headers", path)
    commands = []
    for block in text.split("Load command ")[1:]:
        fields = dict(re.findall(r"^\s*(\w+) (.+?)\s*$", block, re.MULTILINE))
        commands.append((fields.get("cmd"), fields))
    return text, commands


def check_load_commands(path, arch, filetype):
    """A Mach-O of `filetype` (DYLIB or EXECUTE) depending on libSystem alone, with its minimum macOS."""
    text, commands = load_commands(path)
    assert re.search(rf"\b{filetype}\b", text.split("Load command 0")[0]), text[:600]
    dependencies = [f["name"].split(" (offset")[0] for c, f in commands if c == "LC_LOAD_DYLIB"]
    assert dependencies == ["/usr/lib/libSystem.B.dylib"], (arch, dependencies)
    # before macOS 10.14 the minimum is written as LC_VERSION_MIN_MACOSX, from it on as
    # LC_BUILD_VERSION with the platform
    minimum = [f["version"] for c, f in commands if c == "LC_VERSION_MIN_MACOSX"]
    minimum += [f["minos"] for c, f in commands if c == "LC_BUILD_VERSION" and f["platform"] == "macos"]
    assert minimum == [MINIMUM[arch]], (arch, minimum)


def test_a_dylib_depending_on_libsystem_alone_with_its_minimum_macos(library, tmp_path):
    for arch, path in slices(library, tmp_path).items():
        check_load_commands(path, arch, "DYLIB")


def code_signature_pages(path):
    """Checks the code signature of the thin Mach-O `path` as macOS's loader would hash it: the
    CodeDirectory's hash of each page up to its code limit must be the page's. Returns (the
    CodeDirectory's flags, the number of pages)."""
    data = path.read_bytes()
    magic, ncmds = struct.unpack_from("<I", data, 0)[0], struct.unpack_from("<I", data, 16)[0]
    assert magic == 0xFEEDFACF
    offset, signature = 32, None
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, offset)
        if cmd == 0x1D:  # LC_CODE_SIGNATURE
            signature = struct.unpack_from("<II", data, offset + 8)
        offset += size
    assert signature, "no LC_CODE_SIGNATURE"
    start, _ = signature
    blob_magic, _, count = struct.unpack_from(">III", data, start)
    assert blob_magic == 0xFADE0CC0  # an embedded signature (SuperBlob)
    for i in range(count):
        slot, blob = struct.unpack_from(">II", data, start + 12 + 8 * i)
        cd = start + blob
        if slot == 0 and struct.unpack_from(">I", data, cd)[0] == 0xFADE0C02:  # the CodeDirectory
            (_, _, _, flags, hash_offset, _, _, n_code, code_limit, hash_size, hash_type, _,
             page_log2) = struct.unpack_from(">IIIIIIIIIBBBB", data, cd)
            assert hash_type == 2 and hash_size == 32  # SHA-256
            page = 1 << page_log2
            assert n_code == (code_limit + page - 1) // page and code_limit == start
            for k in range(n_code):
                digest = hashlib.sha256(data[k * page:min((k + 1) * page, code_limit)]).digest()
                assert digest == data[cd + hash_offset + 32 * k:cd + hash_offset + 32 * (k + 1)], f"page {k}"
            return flags, n_code
    raise AssertionError("no CodeDirectory in the signature")


def test_the_arm64_code_is_signed_and_the_signature_matches(library, tmp_path):
    for arch, path in slices(library, tmp_path).items():
        if arch == "arm64":
            flags, pages = code_signature_pages(path)
            assert flags & 0x2 and pages > 100  # ad hoc (no certificate), as the linker signs


@pytest.mark.parametrize("arch,triple", [("x86_64", "x86_64-apple-darwin"), ("arm64", "aarch64-apple-darwin")])
def test_the_hasel_command(arch, triple):
    built_here = os.environ.get("CROSS_CLI_TARGETS")
    if built_here is not None and triple not in built_here.split():
        pytest.skip(f"the run's CROSS_CLI_TARGETS leave out {triple} (ci/test.sh; ci/platforms.sh builds it)")
    path = cross_built(triple, "hasel")
    if path is None:
        platform_missing(f"no hasel command for {triple}: `bash ci/platforms.sh` builds it")
    assert llvm("llvm-lipo", "-archs", path).split() == [arch]
    check_load_commands(path, arch, "EXECUTE")
    if arch == "arm64":
        flags, _ = code_signature_pages(path)
        assert flags & 0x2
