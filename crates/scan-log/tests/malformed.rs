//! A truncated or malformed line gives an error naming file and line; the rest still reads.

use std::io::Write;

use scan_log::{LogError, LogOptions, LogReader, LogSource};
use scan_types::LaserSource;

fn flaser(i: usize) -> String {
    format!(
        "FLASER 4 1.0 2.0 3.0 {}.5 {i} 0 0 {i} 0 0 {i}.0 host {i}.0\n",
        i % 9
    )
}

fn carmen_with_damage() -> String {
    let mut s = String::from("# comment\nPARAM x 1 nohost 0\n");
    for i in 0..5 {
        s.push_str(&flaser(i));
        s.push_str("ODOM 0 0 0 0 0 0 0.1 h 0.1\n");
    }
    // Line 13: cut in the middle of the readings; line 14: junk reading.
    s.push_str("FLASER 4 1.0 2.0\n");
    s.push_str("FLASER 4 1.0 2.0 zz 4.0 0 0 0 0 0 0 1.0 host 1.0\n");
    for i in 5..8 {
        s.push_str(&flaser(i));
    }
    // The last line is cut without a newline.
    s.push_str("FLASER 4 1.0 2.0 3.0 4.0 0 0");
    s
}

#[test]
fn bad_lines_are_reported_and_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("damaged.log");
    std::fs::write(&path, carmen_with_damage()).unwrap();
    let items: Vec<_> = LogReader::open(&path, &LogOptions::default())
        .unwrap()
        .collect();
    let ok = items.iter().filter(|r| r.is_ok()).count();
    let errs: Vec<String> = items
        .iter()
        .filter_map(|r| r.as_ref().err())
        .map(|e| e.to_string())
        .collect();
    assert_eq!(ok, 8);
    assert_eq!(errs.len(), 3, "{errs:?}");
    let name = path.display().to_string();
    assert!(
        errs[0].starts_with(&format!("{name}:13 ")) && errs[0].contains("truncated"),
        "{}",
        errs[0]
    );
    assert!(
        errs[1].starts_with(&format!("{name}:14 ")) && errs[1].contains("\"zz\""),
        "{}",
        errs[1]
    );
    assert!(errs[2].starts_with(&format!("{name}:18 ")), "{}", errs[2]);
    // Byte offset of line 13: the length of the 12 lines before it.
    let offset: usize = carmen_with_damage()
        .lines()
        .take(12)
        .map(|l| l.len() + 1)
        .sum();
    assert!(errs[0].contains(&format!("(byte {offset})")), "{}", errs[0]);

    // As a LaserSource: 8 scans, 3 skipped, then end of log.
    let mut src = LogSource::open(&path, &LogOptions::default()).unwrap();
    let mut n = 0;
    let end = loop {
        match src.next_scan() {
            Ok(_) => n += 1,
            Err(e) => break e,
        }
    };
    assert!(matches!(end, LogError::EndOfLog { scans: 8, .. }), "{end}");
    assert_eq!((n, src.skipped(), src.errors().len()), (8, 3, 3));
}

#[test]
fn gzip_reads_like_plain_and_a_cut_gzip_ends_with_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = (0..50).map(flaser).collect::<String>();
    let path = dir.path().join("log.gz");
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(text.as_bytes()).unwrap();
    let gz = enc.finish().unwrap();
    std::fs::write(&path, &gz).unwrap();
    let recs: Vec<_> = LogReader::open(&path, &LogOptions::default())
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(recs.len(), 50);
    assert_eq!(recs[49].pose.unwrap().x_m, 49.0);

    // Cut the compressed file in half: the scans before the cut read, then one error.
    let cut = dir.path().join("cut.log.gz");
    std::fs::write(&cut, &gz[..gz.len() / 2]).unwrap();
    let items: Vec<_> = LogReader::open(&cut, &LogOptions::default())
        .unwrap()
        .collect();
    let last = items.last().unwrap().as_ref().unwrap_err().to_string();
    assert!(last.contains("cut.log.gz"), "{last}");
    assert!(items[..items.len() - 1].iter().all(Result::is_ok));
}

#[test]
fn missing_and_unknown_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let e = LogSource::open(&dir.path().join("nope.log"), &LogOptions::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("nope.log"), "{e}");
    let p = dir.path().join("mystery.txt");
    std::fs::write(&p, "hello world\n").unwrap();
    let e = LogSource::open(&p, &LogOptions::default()).err().unwrap();
    assert!(matches!(e, LogError::UnknownFormat { .. }), "{e}");
    let p = dir.path().join("empty.log");
    std::fs::write(&p, "ODOM 1 2 3\n").unwrap();
    let e = LogSource::open(&p, &LogOptions::default()).err().unwrap();
    assert!(matches!(e, LogError::NoScans { .. }), "{e}");
}
