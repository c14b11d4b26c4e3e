//! FMU states: get/set/free, serialization, corrupted buffers, bit-for-bit replay.

use std::ptr::null_mut;

use super::*;

/// y after each of `n` steps of 0.01 from the current time `t0`, with a changing input.
fn run(fmu: &Fmu, t0: f64, n: usize) -> Vec<u64> {
    (0..n)
        .map(|i| {
            assert_eq!(fmu.set(U, (i as f64 * 0.3).sin()), Fmi2Status::Ok);
            assert_eq!(fmu.step(t0 + i as f64 * 0.01, 0.01), Fmi2Status::Ok);
            fmu.get(Y).to_bits()
        })
        .collect()
}

fn serialize(fmu: &Fmu, state: fmi2FMUstate) -> Vec<u8> {
    let mut size = 0;
    assert_eq!(
        unsafe { toy::fmi2SerializedFMUstateSize(fmu.c, state, &mut size) },
        Fmi2Status::Ok
    );
    let mut bytes = vec![0u8; size];
    assert_eq!(
        unsafe { toy::fmi2SerializeFMUstate(fmu.c, state, bytes.as_mut_ptr().cast(), size) },
        Fmi2Status::Ok
    );
    bytes
}

fn deserialize(fmu: &Fmu, bytes: &[u8]) -> (Fmi2Status, fmi2FMUstate) {
    let mut state = null_mut();
    let status = unsafe {
        toy::fmi2DeSerializeFMUstate(fmu.c, bytes.as_ptr().cast(), bytes.len(), &mut state)
    };
    (status, state)
}

#[test]
fn restored_state_replays_bit_for_bit() {
    let fmu = Fmu::running(0.0);
    run(&fmu, 0.0, 10);
    let mut state = fmu.get_state();
    let first = run(&fmu, 0.1, 50);
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(fmu.c, state) },
        Fmi2Status::Ok
    );
    assert_eq!(run(&fmu, 0.1, 50), first);
    // reuse of a non-NULL state pointer (section 2.1.8)
    let old = state;
    assert_eq!(
        unsafe { toy::fmi2GetFMUstate(fmu.c, &mut state) },
        Fmi2Status::Ok
    );
    assert_eq!(state, old);
    assert_eq!(
        unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut state) },
        Fmi2Status::Ok
    );
    assert!(state.is_null());
    assert_eq!(
        unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut state) },
        Fmi2Status::Ok,
        "*FMUstate NULL is ignored"
    );
    assert_eq!(
        unsafe { toy::fmi2FreeFMUstate(fmu.c, null_mut()) },
        Fmi2Status::Ok,
        "FMUstate NULL is ignored"
    );
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(fmu.c, null_mut()) },
        Fmi2Status::Error
    );
}

/// A state deserialized into a non-NULL FMUstate takes its place, as fmi2GetFMUstate reuses
/// one: the libFuzzer campaign of fmi2_calls found the state there leaked (GetFMUstate, then
/// DeSerializeFMUstate into the same handle).
#[test]
fn a_state_deserialized_into_a_held_one_reuses_it() {
    let fmu = Fmu::running(0.0);
    run(&fmu, 0.0, 10);
    let mut state = fmu.get_state();
    let bytes = serialize(&fmu, state);
    let first = run(&fmu, 0.1, 20);
    let held = state;
    assert_eq!(
        unsafe {
            toy::fmi2DeSerializeFMUstate(fmu.c, bytes.as_ptr().cast(), bytes.len(), &mut state)
        },
        Fmi2Status::Ok
    );
    assert_eq!(state, held);
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(fmu.c, state) },
        Fmi2Status::Ok
    );
    assert_eq!(run(&fmu, 0.1, 20), first);
    assert_eq!(
        unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut state) },
        Fmi2Status::Ok
    );
}

#[test]
fn serialized_state_replays_bit_for_bit_in_another_instance() {
    let fmu = Fmu::running(0.0);
    run(&fmu, 0.0, 10);
    let mut state = fmu.get_state();
    let bytes = serialize(&fmu, state);
    let first = run(&fmu, 0.1, 50);
    unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut state) };

    let other = Fmu::new(); // still instantiated: the state brings its phase along
    let (status, mut restored) = deserialize(&other, &bytes);
    assert_eq!(status, Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(other.c, restored) },
        Fmi2Status::Ok
    );
    assert_eq!(run(&other, 0.1, 50), first);
    assert_eq!(
        serialize(&other, restored),
        bytes,
        "serialization is deterministic"
    );
    unsafe { toy::fmi2FreeFMUstate(other.c, &mut restored) };
}

#[test]
fn corrupted_or_foreign_buffers_are_rejected() {
    let fmu = Fmu::running(0.0);
    run(&fmu, 0.0, 3);
    let mut state = fmu.get_state();
    let bytes = serialize(&fmu, state);
    for len in 0..bytes.len() {
        let (status, s) = deserialize(&fmu, &bytes[..len]);
        assert_eq!(status, Fmi2Status::Error, "truncated to {len}");
        assert!(s.is_null());
    }
    for i in 0..bytes.len() {
        let mut bad = bytes.clone();
        bad[i] ^= 0x10;
        assert_eq!(
            deserialize(&fmu, &bad).0,
            Fmi2Status::Error,
            "byte {i} flipped"
        );
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert_eq!(deserialize(&fmu, &longer).0, Fmi2Status::Error);
    fmu.log.assert_error(&[
        "fmi2DeSerializeFMUstate",
        "truncated",
        "corrupted",
        "bad magic",
    ]);

    // a state of an instance with other start values (other GUID)
    let dir = std::env::temp_dir().join(format!("fmi2-shell-test-guid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tau.txt"), "2.5").unwrap();
    let guid = guid_for(
        &LagCore::model_info(),
        &LagCore::instantiate(InstanceKind::CoSimulation, Some(&dir))
            .unwrap()
            .variables(),
        &LagCore::model_structure(),
    )
    .unwrap();
    let foreign = Fmu::with_guid(&guid, Some(&format!("file://{}", dir.display())));
    assert_eq!(deserialize(&foreign, &bytes).0, Fmi2Status::Error);
    foreign.log.assert_error(&["belongs to GUID"]);
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(foreign.c, state) },
        Fmi2Status::Error
    );
    std::fs::remove_dir_all(dir).unwrap();

    let mut small = vec![0u8; bytes.len() - 1];
    assert_eq!(
        unsafe { toy::fmi2SerializeFMUstate(fmu.c, state, small.as_mut_ptr().cast(), small.len()) },
        Fmi2Status::Error
    );
    fmu.log.assert_error(&["too small"]);
    unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut state) };
}
