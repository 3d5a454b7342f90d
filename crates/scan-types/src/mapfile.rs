//! What goalseek writes into map_server YAML files: one threshold convention and numbers
//! without floating-point noise.

/// `occupied_thresh` of every map_server YAML goalseek writes (and the default it reads).
pub const MAP_OCCUPIED_THRESH: f64 = 0.65;

/// `free_thresh` of every map_server YAML goalseek writes (and the default it reads): with the
/// trinary pixel values goalseek writes (0 occupied, 205 unknown, 254 free), an unknown pixel
/// (occupancy 50/255 = 0.196) is not below it, so it reads back as unknown, not free.
pub const MAP_FREE_THRESH: f64 = 0.196;

/// `v` as text for a file a person reads, without binary floating-point noise: rounded to
/// 1e-9 and written in the shortest form that reads back as that (`-5.85`, not
/// `-5.8500000000000005`), always with a decimal point (`-48.0`), so every number of a
/// map.yaml reads as a float.
pub fn format_decimal(v: f64) -> String {
    if !v.is_finite() || v.abs() >= 1e9 {
        return format!("{v}");
    }
    let r = (v * 1e9).round() / 1e9;
    // -0 reads as 0 in every YAML parser, but say 0.
    let text = format!("{}", if r == 0.0 { 0.0 } else { r });
    if text.contains('.') {
        text
    } else {
        text + ".0"
    }
}

#[cfg(test)]
mod decimal_tests {
    use super::format_decimal;

    #[test]
    fn float_noise_is_dropped_and_values_kept() {
        assert_eq!(format_decimal(-5.8500000000000005), "-5.85");
        assert_eq!(format_decimal(0.1 + 0.2), "0.3");
        assert_eq!(format_decimal(0.05), "0.05");
        assert_eq!(format_decimal(-0.0), "0.0");
        assert_eq!(format_decimal(12.0), "12.0");
        assert_eq!(format_decimal(-48.0), "-48.0");
        assert_eq!(format_decimal(1.0e-10), "0.0");
        assert_eq!(format_decimal(f64::NAN), "NaN");
    }
}
