//! Any bytes as host commands: the emulator must never panic and must keep answering.
#![no_main]

use std::io::{Read, Write};

use libfuzzer_sys::fuzz_target;
use urg_driver::{Emulator, Model};

fuzz_target!(|data: &[u8]| {
    let mut emu = Emulator::fixed(Model::Urg04lx).read_timeout(std::time::Duration::ZERO);
    emu.write_all(data).unwrap();
    emu.write_all(b"\nQT\nVV\n").unwrap();
    let mut buf = [0u8; 4096];
    let mut out = Vec::new();
    for _ in 0..64 {
        match emu.read(&mut buf) {
            Ok(n) => out.extend_from_slice(&buf[..n]),
            Err(_) => break,
        }
        if out.windows(4).any(|w| w == b"VV\n0") {
            break;
        }
    }
    assert!(out.windows(4).any(|w| w == b"VV\n0"));
});
