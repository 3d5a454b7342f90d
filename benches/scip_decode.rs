//! Decode and verify one full URG-04LX MD scan reply (682 three-character values): framing,
//! every line's checksum, the data alphabet, and the values into a reused buffer.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use urg_driver::codec::{self, DataKind, RawScan};

/// A streamed URG-04LX scan reply as the sensor sends it (echo, `99b`, time stamp, 32 data lines).
fn md_reply() -> Vec<u8> {
    let values: Vec<u32> = (0..682u32).map(|i| 20 + (i * 7919) % 5580).collect();
    let mut v = b"MD0044072501000\n99b\n".to_vec();
    codec::encode_scan_body(6_968_830, &values, &[], DataKind::Range3, &mut v);
    v.push(b'\n');
    v
}

fn bench(c: &mut Criterion) {
    let reply = md_reply();
    let mut raw = RawScan::with_capacity(682);
    codec::decode_scan_reply(&reply, DataKind::Range3, &mut raw).expect("valid reply");
    assert_eq!(raw.ranges_mm.len(), 682);
    let mut g = c.benchmark_group("scip_decode");
    g.throughput(Throughput::Bytes(reply.len() as u64));
    g.bench_function("urg_04lx_md_reply", |b| {
        b.iter(|| {
            codec::decode_scan_reply(black_box(&reply), DataKind::Range3, &mut raw).unwrap();
            black_box(raw.ranges_mm[340])
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
