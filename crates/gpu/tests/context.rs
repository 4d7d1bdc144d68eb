//! The device opens (on lavapipe in CI) and reports what it is.

#[test]
fn opens_a_device_or_skips_with_a_message() {
    let Some(ctx) = gpu::require_gpu() else { return };
    println!("adapter: {} ({:?}, driver {})", ctx.info.name, ctx.info.backend, ctx.info.driver);
    assert!(ctx.limits.max_storage_buffer_binding_size >= 1 << 20);
}
