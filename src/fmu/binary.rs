//! The shared libraries an FMU carries: which platform a library was built for, read from its
//! header (ELF, PE or Mach-O, thin or universal), and the `binaries/` folder and file suffix
//! each FMI version gives that platform (FMI 2.0 section 2.3: `linux64`, `win64`, `darwin64`;
//! FMI 3.0 section 2.5.1.1: `x86_64-linux`, `x86_64-windows`, `x86_64-darwin`,
//! `aarch64-darwin`).

use std::fmt;

/// What a library was built for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Platform {
    /// ELF, x86_64.
    Linux,
    /// PE DLL, x86_64.
    Windows,
    /// Mach-O dylib of one architecture.
    Darwin(Arch),
    /// Mach-O universal dylib with an x86_64 and an arm64 slice (`llvm-lipo -create`).
    DarwinUniversal,
}

/// A processor architecture of macOS.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arch {
    X86_64,
    Arm64,
}

impl fmt::Display for Platform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Platform::Linux => "Linux x86_64",
            Platform::Windows => "Windows x86_64",
            Platform::Darwin(Arch::X86_64) => "macOS x86_64",
            Platform::Darwin(Arch::Arm64) => "macOS arm64",
            Platform::DarwinUniversal => "macOS x86_64+arm64",
        })
    }
}

impl Platform {
    /// The library's file suffix.
    pub fn suffix(self) -> &'static str {
        match self {
            Platform::Linux => "so",
            Platform::Windows => "dll",
            Platform::Darwin(_) | Platform::DarwinUniversal => "dylib",
        }
    }

    /// The folder under `binaries/` in an FMU of FMI 2.0 (`fmi3 == false`) or 3.0, or why the
    /// version has none for this library: FMI 2.0's `darwin64` is one file for every Mac, so a
    /// universal one (a thin x86_64 library would not load on arm64); FMI 3.0 names one folder
    /// per architecture, so thin ones.
    pub fn folder(self, fmi3: bool) -> Result<&'static str, String> {
        match (self, fmi3) {
            (Platform::Linux, false) => Ok("linux64"),
            (Platform::Linux, true) => Ok("x86_64-linux"),
            (Platform::Windows, false) => Ok("win64"),
            (Platform::Windows, true) => Ok("x86_64-windows"),
            (Platform::DarwinUniversal, false) => Ok("darwin64"),
            (Platform::Darwin(_), false) => Err(
                "FMI 2.0's darwin64 takes a universal library of both Mac architectures (llvm-lipo -create)"
                    .into(),
            ),
            (Platform::Darwin(Arch::X86_64), true) => Ok("x86_64-darwin"),
            (Platform::Darwin(Arch::Arm64), true) => Ok("aarch64-darwin"),
            (Platform::DarwinUniversal, true) => {
                Err("FMI 3.0 takes one library per Mac architecture, not a universal one".into())
            }
        }
    }
}

fn u16_le(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn u32_le(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn u32_be(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// Mach-O CPU types (`mach/machine.h`).
const CPU_TYPE_X86_64: u32 = 0x0100_0007;
const CPU_TYPE_ARM64: u32 = 0x0100_000c;

fn mach_arch(cpu: u32) -> Option<Arch> {
    match cpu {
        CPU_TYPE_X86_64 => Some(Arch::X86_64),
        CPU_TYPE_ARM64 => Some(Arch::Arm64),
        _ => None,
    }
}

/// The platform of the shared library `b`, or what it is instead.
pub fn platform_of(b: &[u8]) -> Result<Platform, String> {
    if b.starts_with(b"\x7fELF") {
        // 64-bit (class 2), little-endian, a shared object (ET_DYN) for x86_64 (EM_X86_64)
        return if b.get(4..6) == Some(&[2, 1])
            && u16_le(b, 16) == Some(3)
            && u16_le(b, 18) == Some(62)
        {
            Ok(Platform::Linux)
        } else {
            Err("an ELF file, but not an x86_64 shared library".into())
        };
    }
    if b.starts_with(b"MZ") {
        // the PE header: machine AMD64, characteristics with IMAGE_FILE_DLL
        let pe = u32_le(b, 0x3c).map(|o| o as usize);
        let is_dll = pe.is_some_and(|o| {
            b.get(o..o + 4) == Some(b"PE\0\0")
                && u16_le(b, o + 4) == Some(0x8664)
                && u16_le(b, o + 22).is_some_and(|c| c & 0x2000 != 0)
        });
        return if is_dll {
            Ok(Platform::Windows)
        } else {
            Err("a Windows executable, but not an x86_64 DLL".into())
        };
    }
    if u32_le(b, 0) == Some(0xfeed_facf) {
        // 64-bit Mach-O, file type MH_DYLIB
        return match (mach_arch(u32_le(b, 4).unwrap_or(0)), u32_le(b, 12)) {
            (Some(arch), Some(6)) => Ok(Platform::Darwin(arch)),
            _ => Err("a Mach-O file, but not an x86_64 or arm64 dylib".into()),
        };
    }
    if u32_be(b, 0) == Some(0xcafe_babe) {
        // universal: the big-endian count of slices, then 20 bytes each, the CPU type first
        let n = u32_be(b, 4).unwrap_or(0) as usize;
        let mut arches: Vec<_> = (0..n.min(8))
            .map(|i| u32_be(b, 8 + 20 * i).and_then(mach_arch))
            .collect();
        arches.sort_by_key(|a| a.map(|a| a as u8));
        return if arches == [Some(Arch::X86_64), Some(Arch::Arm64)] {
            Ok(Platform::DarwinUniversal)
        } else {
            Err("a universal Mach-O file, but not of exactly an x86_64 and an arm64 slice".into())
        };
    }
    Err("not a shared library (ELF, PE or Mach-O)".into())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The first bytes of a library of `platform`, enough for [`platform_of`].
    pub(crate) fn header(platform: Platform) -> Vec<u8> {
        let mut b = vec![0u8; 0x100];
        match platform {
            Platform::Linux => {
                b[..4].copy_from_slice(b"\x7fELF");
                b[4..6].copy_from_slice(&[2, 1]);
                b[16..18].copy_from_slice(&3u16.to_le_bytes());
                b[18..20].copy_from_slice(&62u16.to_le_bytes());
            }
            Platform::Windows => {
                b[..2].copy_from_slice(b"MZ");
                b[0x3c..0x40].copy_from_slice(&0x80u32.to_le_bytes());
                b[0x80..0x84].copy_from_slice(b"PE\0\0");
                b[0x84..0x86].copy_from_slice(&0x8664u16.to_le_bytes());
                b[0x96..0x98].copy_from_slice(&0x2022u16.to_le_bytes());
            }
            Platform::Darwin(arch) => {
                let cpu = match arch {
                    Arch::X86_64 => CPU_TYPE_X86_64,
                    Arch::Arm64 => CPU_TYPE_ARM64,
                };
                b[..4].copy_from_slice(&0xfeed_facfu32.to_le_bytes());
                b[4..8].copy_from_slice(&cpu.to_le_bytes());
                b[12..16].copy_from_slice(&6u32.to_le_bytes());
            }
            Platform::DarwinUniversal => {
                b[..4].copy_from_slice(&0xcafe_babeu32.to_be_bytes());
                b[4..8].copy_from_slice(&2u32.to_be_bytes());
                b[8..12].copy_from_slice(&CPU_TYPE_ARM64.to_be_bytes());
                b[28..32].copy_from_slice(&CPU_TYPE_X86_64.to_be_bytes());
            }
        }
        b
    }

    const ALL: [Platform; 4] = [
        Platform::Linux,
        Platform::Windows,
        Platform::Darwin(Arch::X86_64),
        Platform::Darwin(Arch::Arm64),
    ];

    #[test]
    fn each_header_is_read_as_its_platform() {
        for p in ALL.into_iter().chain([Platform::DarwinUniversal]) {
            assert_eq!(platform_of(&header(p)), Ok(p), "{p}");
        }
    }

    #[test]
    fn other_files_are_refused_with_what_they_are() {
        let mut elf32 = header(Platform::Linux);
        elf32[4] = 1;
        let mut exe = header(Platform::Windows);
        exe[0x96] = 0x22;
        exe[0x97] = 0;
        let mut one_slice = header(Platform::DarwinUniversal);
        one_slice[7] = 1;
        for (bytes, what) in [
            (b"not elf".to_vec(), "not a shared library"),
            (elf32, "not an x86_64 shared library"),
            (exe, "not an x86_64 DLL"),
            (one_slice, "not of exactly an x86_64 and an arm64 slice"),
        ] {
            let e = platform_of(&bytes).unwrap_err();
            assert!(e.contains(what), "{e}");
        }
    }

    #[test]
    fn each_version_has_its_folders() {
        let folders = |fmi3| ALL.map(|p| p.folder(fmi3).ok());
        assert_eq!(folders(false), [Some("linux64"), Some("win64"), None, None]);
        assert_eq!(Platform::DarwinUniversal.folder(false), Ok("darwin64"));
        assert_eq!(
            folders(true),
            [
                Some("x86_64-linux"),
                Some("x86_64-windows"),
                Some("x86_64-darwin"),
                Some("aarch64-darwin")
            ]
        );
        assert!(Platform::DarwinUniversal.folder(true).is_err());
    }
}
