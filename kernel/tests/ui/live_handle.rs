// A live handle vouches that its object is alive: only the kernel, under
// `unsafe`, makes one.
#![forbid(unsafe_code)]
use rtk_kernel::abi::ObjectModuleRef;
use rtk_kernel::sdk::LiveObject;

fn main() {
    fn forge(this: *mut std::ffi::c_void, class: ObjectModuleRef) -> LiveObject {
        unsafe { LiveObject::new(this, class) }
    }
    let _ = forge;
}
