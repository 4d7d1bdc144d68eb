//! Tests of `camera_control.rs`.

use super::*;

fn control() -> CameraControl {
    let camera =
        Camera { eye: Vec3::new(0.0, 1.0, 4.0), center: Vec3::new(0.0, 1.0, 0.0), up: Vec3::Y, fov_y_deg: 40.0 };
    CameraControl::new(camera, 3.0)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-4
}

#[test]
fn orbit_keeps_the_distance_to_the_centre_and_the_centre() {
    let mut c = control();
    let before = c.camera();
    for (yaw, pitch) in [(0.3, 0.2), (-1.0, 0.5), (2.5, -0.7), (0.0, 3.0), (0.1, -6.0)] {
        c.orbit(yaw, pitch);
        let cam = c.camera();
        assert!(((cam.eye - cam.center).length() - 4.0).abs() < 1e-4, "{cam:?}");
        assert_eq!(cam.center, before.center);
        assert!(cam.validate().is_ok(), "{cam:?}");
    }
}

#[test]
fn orbit_directions_follow_the_documentation() {
    let mut c = control();
    c.orbit(0.5, 0.0);
    // Eye turned to its left: from +z towards −x.
    assert!(c.camera().eye.x < 0.0, "{:?}", c.camera());
    assert!((c.camera().eye.y - 1.0).abs() < 1e-5);
    let mut c = control();
    c.orbit(0.0, 0.5);
    assert!(c.camera().eye.y > 1.0, "pitch up raises the eye");
    // Stops short of the pole instead of flipping over.
    c.orbit(0.0, 10.0);
    let cam = c.camera();
    assert!(cam.eye.z > 0.0 && cam.validate().is_ok(), "{cam:?}");
}

#[test]
fn pan_moves_eye_and_centre_together() {
    let mut c = control();
    let before = c.camera();
    c.pan(0.25, -0.1);
    let cam = c.camera();
    assert!(close(cam.eye - before.eye, cam.center - before.center));
    // Dragging right moves the camera left (scene follows the cursor), dragging up
    // moves it down.
    assert!(cam.center.x < 0.0 && cam.center.y < 1.0, "{cam:?}");
    // A drag of one image height moves the centre by the visible height at its depth.
    let mut c = control();
    c.pan(0.0, 1.0);
    let height = 2.0 * 4.0 * 20f32.to_radians().tan();
    assert!(close(c.camera().center, Vec3::new(0.0, 1.0 + height, 0.0)), "{:?}", c.camera());
}

#[test]
fn dolly_never_passes_the_centre() {
    let mut c = control();
    c.dolly(1.0);
    assert!(((c.camera().eye - c.camera().center).length() - 3.6).abs() < 1e-4);
    for _ in 0..1000 {
        c.dolly(5.0);
        let cam = c.camera();
        assert!(cam.eye.z > cam.center.z, "eye passed the centre: {cam:?}");
        assert!(cam.validate().is_ok());
    }
    c.dolly(-2.0);
    assert!(c.camera().eye.z > 0.0);
    let mut c = control();
    c.dolly(-1.0);
    assert!(((c.camera().eye - c.camera().center).length() - 4.0 / 0.9).abs() < 1e-4);
}

#[test]
fn fly_moves_eye_and_centre_together() {
    let mut c = control();
    let before = c.camera();
    c.fly(1.0, 0.0, 0.0);
    let cam = c.camera();
    assert!(close(cam.eye - before.eye, Vec3::new(0.0, 0.0, -c.step())));
    assert!(close(cam.center - before.center, cam.eye - before.eye));
    c.fly(0.0, 2.0, -1.0);
    let after = c.camera();
    assert!(close(after.eye - cam.eye, Vec3::new(2.0 * c.step(), -c.step(), 0.0)), "{after:?}");
    assert!(close(after.center - cam.center, after.eye - cam.eye));
    c.reset();
    assert_eq!(c.camera(), before);
}

#[test]
fn turn_keeps_the_eye_and_the_distance() {
    let mut c = control();
    c.turn(0.4, 0.3);
    let cam = c.camera();
    assert_eq!(cam.eye, Vec3::new(0.0, 1.0, 4.0));
    assert!(((cam.center - cam.eye).length() - 4.0).abs() < 1e-4);
    assert!(cam.center.x < 0.0 && cam.center.y > 1.0, "turned left and up: {cam:?}");
    c.turn(0.0, -10.0);
    assert!(c.camera().validate().is_ok());
}
