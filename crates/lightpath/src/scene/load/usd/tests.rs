//! The colour of a temperature and the value conversions, beside the code.

use super::lights::blackbody_rgb;
use super::stage;
use openusd::sdf::Value;

#[test]
fn colour_temperature_is_white_at_6500_k_and_warm_below() {
    let white = blackbody_rgb(6500.0);
    assert!(white.iter().all(|c| (c - 1.0).abs() < 1e-4), "{white:?}");
    // Warmer as the temperature falls, cooler above 6500 K; luminance stays 1.
    let (a, b, c) = (
        blackbody_rgb(2000.0),
        blackbody_rgb(4000.0),
        blackbody_rgb(10000.0),
    );
    assert!(a[2] / a[0] < b[2] / b[0] && b[2] / b[0] < 1.0 && c[2] / c[0] > 1.0);
    for k in [a, b, c] {
        let y = 0.2126 * k[0] + 0.7152 * k[1] + 0.0722 * k[2];
        assert!((y - 1.0).abs() < 1e-4);
    }
}

#[test]
fn values_of_any_precision_read_as_f32() {
    assert_eq!(stage::f32_of(&Value::Double(0.25)), Some(0.25));
    assert_eq!(stage::f32_of(&Value::Int(3)), Some(3.0));
    assert_eq!(stage::f32_of(&Value::String("x".into())), None);
    let v = Value::Vec3dVec(vec![[1.0, 2.0, 3.0].into()]);
    assert_eq!(stage::vec3_array(v), Some(vec![[1.0, 2.0, 3.0]]));
    assert_eq!(
        stage::int_array(Value::Int64Vec(vec![-1, 7])),
        Some(vec![-1, 7])
    );
}
