//! FMU states through the FMI 3.0 functions: a restored or deserialized state replays bit
//! for bit; corrupted and foreign bytes are refused.

use std::ptr::null_mut;

use super::{Cs, v3, vr};
use crate::fmi3::types::*;

/// Steps `n` times with U2 = 80 V and returns h2.
fn run(cs: &mut Cs, n: usize) -> f64 {
    assert_eq!(cs.set(&[vr("U2")], &[80.0]), Fmi3Status::Ok);
    for _ in 0..n {
        assert_eq!(cs.step(1e-3).0, Fmi3Status::Ok);
    }
    cs.get(&[vr("h2")]).1[0]
}

fn serialize(cs: &Cs, state: fmi3FMUState) -> Vec<u8> {
    let mut size = 0;
    unsafe {
        assert_eq!(
            v3::fmi3SerializedFMUStateSize(cs.c, state, &mut size),
            Fmi3Status::Ok
        );
        let mut bytes = vec![0u8; size];
        assert_eq!(
            v3::fmi3SerializeFMUState(cs.c, state, bytes.as_mut_ptr(), size),
            Fmi3Status::Ok
        );
        bytes
    }
}

#[test]
fn a_restored_state_replays_bit_for_bit() {
    let mut cs = Cs::new(false);
    cs.init();
    run(&mut cs, 20);
    let mut state: fmi3FMUState = null_mut();
    unsafe { assert_eq!(v3::fmi3GetFMUState(cs.c, &mut state), Fmi3Status::Ok) };
    let t0 = cs.t;
    let first = run(&mut cs, 30);
    let bytes = serialize(&cs, state);
    unsafe { assert_eq!(v3::fmi3SetFMUState(cs.c, state), Fmi3Status::Ok) };
    cs.t = t0;
    assert_eq!(run(&mut cs, 30).to_bits(), first.to_bits());
    // deserialized into a second instance
    let mut other = Cs::new(false);
    let mut copy: fmi3FMUState = null_mut();
    unsafe {
        assert_eq!(
            v3::fmi3DeserializeFMUState(other.c, bytes.as_ptr(), bytes.len(), &mut copy),
            Fmi3Status::Ok
        );
        assert_eq!(v3::fmi3SetFMUState(other.c, copy), Fmi3Status::Ok);
        assert_eq!(v3::fmi3FreeFMUState(other.c, &mut copy), Fmi3Status::Ok);
        assert!(copy.is_null());
    }
    other.t = t0;
    assert_eq!(run(&mut other, 30).to_bits(), first.to_bits());
    // a buffer too small
    let mut small = [0u8; 4];
    let s = unsafe { v3::fmi3SerializeFMUState(cs.c, state, small.as_mut_ptr(), 4) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3SerializeFMUState", "buffer of 4 bytes is too small"]);
    unsafe { assert_eq!(v3::fmi3FreeFMUState(cs.c, &mut state), Fmi3Status::Ok) };
}

#[test]
fn corrupted_truncated_and_foreign_bytes_are_refused() {
    let mut cs = Cs::new(false);
    cs.init();
    run(&mut cs, 3);
    let mut state: fmi3FMUState = null_mut();
    unsafe { assert_eq!(v3::fmi3GetFMUState(cs.c, &mut state), Fmi3Status::Ok) };
    let bytes = serialize(&cs, state);
    unsafe { v3::fmi3FreeFMUState(cs.c, &mut state) };
    let mut flipped = bytes.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0x10;
    let cases: [(&[u8], &str); 4] = [
        (&flipped, "corrupted"),
        (&bytes[..bytes.len() - 3], "corrupted or truncated"),
        (&bytes[..5], "bad magic"),
        (b"FMI2RSST and more", "bad magic"),
    ];
    for (data, what) in cases {
        let mut out: fmi3FMUState = null_mut();
        let s = unsafe { v3::fmi3DeserializeFMUState(cs.c, data.as_ptr(), data.len(), &mut out) };
        assert_eq!(s, Fmi3Status::Error, "{what}");
        assert!(out.is_null());
        cs.log.assert_error(&["fmi3DeserializeFMUState", what]);
    }
    let s = unsafe { v3::fmi3DeserializeFMUState(cs.c, std::ptr::null(), 10, &mut state) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log.assert_error(&["serializedState is NULL"]);
    assert_eq!(
        unsafe { v3::fmi3SetFMUState(cs.c, null_mut()) },
        Fmi3Status::Error
    );
    cs.log
        .assert_error(&["fmi3SetFMUState", "FMUState is NULL"]);
}
