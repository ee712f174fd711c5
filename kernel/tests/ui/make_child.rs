// A plugin cannot wrap a pointer of its own making as a child.
use rtk_kernel::abi::ObjectRef;
use rtk_kernel::{Child, InstanceData};

fn main() {
    fn forge(r: ObjectRef) -> Child {
        Child::new(r, InstanceData::NONE)
    }
    let _ = forge;
}
