//! The generators that turn each declaration of `rtk_abi::entries` into the
//! two safe sides of the boundary:
//!
//! - [`__shims!`](crate::__shims): for the side that implements a record
//!   (a plugin), one `unsafe extern "C"` shim per entry that turns the raw
//!   arguments back into references ([`FromRaw`](crate::FromRaw)), runs the
//!   trait method under `catch_unwind`, and records a failure in the trace
//!   context (hot entries) or the error sink (cold ones); the record
//!   builder; one `Install` method per capability.
//! - [`__host_shims!`](crate::__host_shims): the same for the one record the
//!   host implements (the scene services), without `catch_unwind` (host code
//!   is pure dispatch; a panic there is a bug and aborts with its message).
//! - [`__callers!`](crate::__callers): for the side that calls a record,
//!   one safe method per entry on a `Live*` handle (whose unsafe constructor
//!   vouches that the object is alive), taking references and returning
//!   `Option`s and `Result`s.
//!
//! Each generator emits one item per entry through a helper macro, so only
//! the record (in `rtk-abi`) needs to walk its entries one at a time.

/// The safe type of a raw argument, on the calling side.
#[doc(hidden)]
#[macro_export]
macro_rules! __safe_ty {
    (*const SceneRef) => { &$crate::Scene };
    (*const $t:ty) => { &$t };
    (*mut $t:ty) => { &mut $t };
    (Nullable<$t:ty>) => { Option<&$t> };
    (Span<$t:ty>) => { &[$t] };
    (SpanMut<$t:ty>) => { &mut [$t] };
    (Float3) => { impl Into<$crate::abi::Float3> };
    ($t:ty) => { $t };
}

/// A calling side's argument as its raw type.
#[doc(hidden)]
#[macro_export]
macro_rules! __to_raw {
    ($a:ident : *const SceneRef) => {
        $a.raw() as *const $crate::abi::SceneRef
    };
    ($a:ident : *const $t:ty) => {
        $a as *const $t
    };
    ($a:ident : *mut $t:ty) => {
        $a as *mut $t
    };
    ($a:ident : Nullable<$t:ty>) => {
        $a.map_or(::std::ptr::null(), |r| r as *const $t)
    };
    ($a:ident : Span<$t:ty>) => {
        $crate::abi::Span::of($a)
    };
    ($a:ident : SpanMut<$t:ty>) => {
        $crate::abi::SpanMut::of($a)
    };
    ($a:ident : Float3) => {
        $a.into()
    };
    ($a:ident : $t:ty) => {
        $a
    };
}

/// `this` as the implementing type, shared (`const`) or exclusive (`mut`).
#[doc(hidden)]
#[macro_export]
macro_rules! __this {
    (const, $t:ty, $this:ident) => {
        $crate::shims::obj::<$t>($this)
    };
    (mut, $t:ty, $this:ident) => {
        $crate::shims::obj_mut::<$t>($this)
    };
}

/// Shims, the record builder and the `Install` methods of one record, for
/// a plugin: `rtk_abi::object_entries!(rtk_sdk::__shims, object)` writes
/// `mod object` with `module::<T, D>()`.
#[doc(hidden)]
#[macro_export]
macro_rules! __shims {
    (config [$modname:ident]
     kind $kind:ident, module $module:ident, prefix $prefix:ident, trait $tr:ident;
     entries { $( $(#[$m:meta])* $temp:ident $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* )
                  -> $form:ident [$($ret:tt)*] $(= $fb:expr)? ; )* }
     caps { $( $(#[$cm:meta])* $cap:ident {
         $( $(#[$m2:meta])* $temp2:ident $name2:ident ( $recv2:tt $(, ($a2:ident : $($t2:tt)*))* )
            -> $form2:ident [$($ret2:tt)*] $(= $fb2:expr)? ; )* } )* }
     flags { $( $(#[$fm:meta])* $fcap:ident $flag:ident ; )* }
     appended { $( $(#[$m3:meta])* $temp3:ident $name3:ident ( $recv3:tt $(, ($a3:ident : $($t3:tt)*))* )
                   -> $form3:ident [$($ret3:tt)*] $(= $fb3:expr)? ; )* }
     appended_caps { $( $(#[$acm:meta])* $acap:ident {
         $( $(#[$m4:meta])* $temp4:ident $name4:ident ( $recv4:tt $(, ($a4:ident : $($t4:tt)*))* )
            -> $form4:ident [$($ret4:tt)*] $(= $fb4:expr)? ; )* } )* }
    ) => {
        #[doc = concat!("The shims of the `", stringify!($kind), "` record, generated from its declaration.")]
        pub mod $modname {
            #![allow(unused_imports)]
            use super::*;
            use $crate::abi::*;
            use $crate::shims::{Decl, Install};
            use ::std::ffi::c_void;

            $( $crate::__shim!{ $tr; $temp $name ( $recv $(, ($a : $($t)*))* ) -> $form [$($ret)*] $(= $fb)? } )*
            $( $( $crate::__shim!{ $cap; $temp2 $name2 ( $recv2 $(, ($a2 : $($t2)*))* ) -> $form2 [$($ret2)*] $(= $fb2)? } )* )*
            $( $crate::__shim!{ $tr; $temp3 $name3 ( $recv3 $(, ($a3 : $($t3)*))* ) -> $form3 [$($ret3)*] $(= $fb3)? } )*
            $( $( $crate::__shim!{ $acap; $temp4 $name4 ( $recv4 $(, ($a4 : $($t4)*))* ) -> $form4 [$($ret4)*] $(= $fb4)? } )* )*

            /// The record of `T`, before its capabilities are installed:
            /// every entry of the kind's trait, no capability, no flag.
            pub fn module<T: $tr, D: Decl>() -> $module {
                $module {
                    meta: $crate::shims::meta::<D>(),
                    create: $crate::shims::create::<T>,
                    destroy: $crate::shims::destroy::<T>,
                    $( $name: $name::<T, D>, )*
                    $( $( $name2: None, )* )*
                    $( $flag: false, )*
                    abi_minor: ABI_MINOR,
                    $( $name3: Some($name3::<T, D>), )*
                    $( $( $name4: None, )* )*
                }
            }

            $(
                #[allow(non_snake_case)]
                impl<T: $cap, D: Decl> Install<T, D> {
                    $(#[$cm])*
                    pub fn $cap(m: &mut $module) {
                        $( m.$name2 = Some($name2::<T, D>); )*
                    }
                }
            )*
            $(
                #[allow(non_snake_case)]
                impl<T: $fcap, D: Decl> Install<T, D> {
                    $(#[$fm])*
                    pub fn $fcap(m: &mut $module) {
                        m.$flag = true;
                    }
                }
            )*
            $(
                #[allow(non_snake_case)]
                impl<T: $acap, D: Decl> Install<T, D> {
                    $(#[$acm])*
                    pub fn $acap(m: &mut $module) {
                        $( m.$name4 = Some($name4::<T, D>); )*
                    }
                }
            )*
        }
    };
}

/// One plugin-side shim, by calling convention.
#[doc(hidden)]
#[macro_export]
macro_rules! __shim {
    ($bound:ident; hot $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> plain [$($ret:tt)*] = $fb:expr) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T`.")]
        ///
        /// # Safety
        /// The record's contract: `this` is a live `T` made by this plugin,
        /// `ctx` is exclusive, every pointer is valid for the call.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void, ctx: *mut TraceCtx $(, $a: $($t)*)*
        ) -> $($ret)* {
            // SAFETY: the caller keeps the record's contract (above); the
            // conversions turn its pointers into references for the call.
            unsafe {
                $crate::shims::hot::<D, _>(ctx, stringify!($name), $fb, |ctx| {
                    <T as $bound>::$name($crate::__this!($recv, T, this), ctx $(, $crate::FromRaw::from_raw($a))*)
                })
            }
        }
    };
    ($bound:ident; hot $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T`.")]
        ///
        /// # Safety
        /// As for every hot entry: `this` live, `ctx` exclusive, pointers valid.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void, ctx: *mut TraceCtx $(, $a: $($t)*)*
        ) {
            // SAFETY: the record's contract, as for every hot entry.
            unsafe {
                $crate::shims::hot::<D, _>(ctx, stringify!($name), (), |ctx| {
                    <T as $bound>::$name($crate::__this!($recv, T, this), ctx $(, $crate::FromRaw::from_raw($a))*)
                })
            }
        }
    };
    ($bound:ident; hot $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> option [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T`: writes `out` when there is an answer.")]
        ///
        /// # Safety
        /// As for every hot entry; `out` is valid for a write.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void, ctx: *mut TraceCtx $(, $a: $($t)*)*, out: *mut $($ret)*
        ) -> bool {
            // SAFETY: the record's contract, as for every hot entry; `out`
            // is written only with an answer.
            unsafe {
                $crate::shims::hot::<D, _>(ctx, stringify!($name), false, |ctx| {
                    $crate::shims::write_some(out,
                        <T as $bound>::$name($crate::__this!($recv, T, this), ctx $(, $crate::FromRaw::from_raw($a))*))
                })
            }
        }
    };
    ($bound:ident; cold $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> status []) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T`.")]
        ///
        /// # Safety
        /// The record's contract: `this` is a live `T` made by this plugin
        /// (exclusive for a `mut` entry), every pointer valid for the call.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void $(, $a: $($t)*)*, sink: ErrSink
        ) -> i32 {
            // SAFETY: the record's contract (above).
            unsafe {
                $crate::shims::cold(sink, || {
                    <T as $bound>::$name($crate::__this!($recv, T, this) $(, $crate::FromRaw::from_raw($a))*)
                })
            }
        }
    };
    ($bound:ident; cold $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T` (which cannot fail but by panicking).")]
        ///
        /// # Safety
        /// As for every cold entry.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void $(, $a: $($t)*)*, sink: ErrSink
        ) -> i32 {
            // SAFETY: the record's contract, as for every cold entry.
            unsafe {
                $crate::shims::cold(sink, || {
                    <T as $bound>::$name($crate::__this!($recv, T, this) $(, $crate::FromRaw::from_raw($a))*);
                    Ok(())
                })
            }
        }
    };
    ($bound:ident; cold $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> value [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T`: its answer into `out`.")]
        ///
        /// # Safety
        /// As for every cold entry; `out` is valid for a write.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void $(, $a: $($t)*)*, out: *mut $($ret)*, sink: ErrSink
        ) -> i32 {
            // SAFETY: the record's contract, as for every cold entry; `out`
            // is written once, with a checked answer.
            unsafe {
                $crate::shims::cold(sink, || {
                    let v = <T as $bound>::$name($crate::__this!($recv, T, this) $(, $crate::FromRaw::from_raw($a))*);
                    *out = $crate::ToRawAnswer::to_raw_answer(v)?;
                    Ok(())
                })
            }
        }
    };
    ($bound:ident; cold $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* ) -> result [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` entry of `T`: its answer into `out`, or an error.")]
        ///
        /// # Safety
        /// As for every cold entry; `out` is valid for a write.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            this: *$recv c_void $(, $a: $($t)*)*, out: *mut $($ret)*, sink: ErrSink
        ) -> i32 {
            // SAFETY: the record's contract, as for every cold entry.
            unsafe {
                $crate::shims::cold(sink, || {
                    let v = <T as $bound>::$name($crate::__this!($recv, T, this) $(, $crate::FromRaw::from_raw($a))*)?;
                    *out = $crate::ToRawAnswer::to_raw_answer(v)?;
                    Ok(())
                })
            }
        }
    };
    ($bound:ident; ctor $name:ident ( new $(, ($a:ident : $($t:tt)*))* ) -> status []) => {
        #[doc = concat!("The `", stringify!($name), "` constructor of `T`.")]
        ///
        /// # Safety
        /// Every pointer is valid for the call.
        pub unsafe extern "C" fn $name<T: $bound, D: Decl>(
            $($a: $($t)*,)* env: *const CreateEnv, sink: ErrSink
        ) -> *mut c_void {
            let mut made: *mut c_void = ::std::ptr::null_mut();
            // SAFETY: the host passes valid arguments and a valid environment.
            unsafe {
                $crate::shims::cold(sink, || {
                    let env = $crate::shims::env_of(&*env);
                    let obj = <T as $bound>::$name($($crate::FromRaw::from_raw($a),)* &env)?;
                    made = Box::into_raw(Box::new(obj)) as *mut c_void;
                    Ok(())
                });
            }
            made
        }
    };
}

/// Host-side shims and the record builder for the scene services:
/// `rtk_abi::scene_entries!(rtk_sdk::__host_shims, services)`.
#[doc(hidden)]
#[macro_export]
macro_rules! __host_shims {
    (config [$modname:ident]
     kind $kind:ident, module $module:ident, prefix $prefix:ident, trait $tr:ident;
     entries { $( $(#[$m:meta])* $temp:ident $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* )
                  -> $form:ident [$($ret:tt)*] $(= $fb:expr)? ; )* }
     caps {}
     flags {}
     appended { $( $(#[$m3:meta])* $temp3:ident $name3:ident ( $recv3:tt $(, ($a3:ident : $($t3:tt)*))* )
                   -> $form3:ident [$($ret3:tt)*] $(= $fb3:expr)? ; )* }
     appended_caps {}
    ) => {
        #[doc = concat!("The shims of the `", stringify!($kind), "` record, generated from its declaration.")]
        pub mod $modname {
            #![allow(unused_imports)]
            use super::*;
            use $crate::abi::*;
            use ::std::ffi::c_void;

            $( $crate::__host_shim!{ $tr; $temp $name ( $recv $(, ($a : $($t)*))* ) -> $form [$($ret)*] } )*
            $( $crate::__host_shim!{ $tr; $temp3 $name3 ( $recv3 $(, ($a3 : $($t3)*))* ) -> $form3 [$($ret3)*] } )*

            /// The record of host type `H`.
            pub fn module<H: $tr>() -> $module {
                $module {
                    $( $name: $name::<H>, )*
                    abi_minor: ABI_MINOR,
                    $( $name3: Some($name3::<H>), )*
                }
            }
        }
    };
}

/// One host-side shim.
#[doc(hidden)]
#[macro_export]
macro_rules! __host_shim {
    ($tr:ident; hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> plain [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` service of `H`.")]
        ///
        /// # Safety
        /// `this` is the live `H` the record was bound to; `ctx` exclusive;
        /// every pointer valid for the call.
        pub unsafe extern "C" fn $name<H: $tr>(this: *const c_void, ctx: *mut TraceCtx $(, $a: $($t)*)*) -> $($ret)* {
            // SAFETY: the record's contract (above).
            unsafe { <H as $tr>::$name(&*(this as *const H), &mut *ctx $(, $crate::FromRaw::from_raw($a))*) }
        }
    };
    ($tr:ident; hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        #[doc = concat!("The `", stringify!($name), "` service of `H`.")]
        ///
        /// # Safety
        /// As for every hot service.
        pub unsafe extern "C" fn $name<H: $tr>(this: *const c_void, ctx: *mut TraceCtx $(, $a: $($t)*)*) {
            // SAFETY: the record's contract, as for every hot service.
            unsafe { <H as $tr>::$name(&*(this as *const H), &mut *ctx $(, $crate::FromRaw::from_raw($a))*) }
        }
    };
    ($tr:ident; hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> option [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` service of `H`.")]
        ///
        /// # Safety
        /// As for every hot service; `out` valid for a write.
        pub unsafe extern "C" fn $name<H: $tr>(this: *const c_void, ctx: *mut TraceCtx $(, $a: $($t)*)*, out: *mut $($ret)*) -> bool {
            // SAFETY: the record's contract, as for every hot service.
            unsafe {
                $crate::shims::write_some(out,
                    <H as $tr>::$name(&*(this as *const H), &mut *ctx $(, $crate::FromRaw::from_raw($a))*))
            }
        }
    };
    ($tr:ident; pure $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> plain [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` service of `H`.")]
        ///
        /// # Safety
        /// `this` is the live `H` the record was bound to.
        pub unsafe extern "C" fn $name<H: $tr>(this: *const c_void $(, $a: $($t)*)*) -> $($ret)* {
            // SAFETY: the record's contract (above).
            unsafe { <H as $tr>::$name(&*(this as *const H) $(, $crate::FromRaw::from_raw($a))*) }
        }
    };
    ($tr:ident; pure $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> option [$($ret:tt)*]) => {
        #[doc = concat!("The `", stringify!($name), "` service of `H`.")]
        ///
        /// # Safety
        /// As for every pure service; `out` valid for a write.
        pub unsafe extern "C" fn $name<H: $tr>(this: *const c_void $(, $a: $($t)*)*, out: *mut $($ret)*) -> bool {
            // SAFETY: the record's contract, as for every pure service.
            unsafe {
                $crate::shims::write_some(out,
                    <H as $tr>::$name(&*(this as *const H) $(, $crate::FromRaw::from_raw($a))*))
            }
        }
    };
}

/// Safe callers of one record on its `Live*` handle:
/// `rtk_abi::object_entries!(rtk_sdk::__callers, LiveObject)`.
#[doc(hidden)]
#[macro_export]
macro_rules! __callers {
    (config [$live:ident]
     kind $kind:ident, module $module:ident, prefix $prefix:ident, trait $tr:ident;
     entries { $( $(#[$m:meta])* $temp:ident $name:ident ( $recv:tt $(, ($a:ident : $($t:tt)*))* )
                  -> $form:ident [$($ret:tt)*] $(= $fb:expr)? ; )* }
     caps { $( $(#[$cm:meta])* $cap:ident {
         $( $(#[$m2:meta])* $temp2:ident $name2:ident ( $recv2:tt $(, ($a2:ident : $($t2:tt)*))* )
            -> $form2:ident [$($ret2:tt)*] $(= $fb2:expr)? ; )* } )* }
     flags { $( $(#[$fm:meta])* $fcap:ident $flag:ident ; )* }
     appended { $( $(#[$m3:meta])* $temp3:ident $name3:ident ( $recv3:tt $(, ($a3:ident : $($t3:tt)*))* )
                   -> $form3:ident [$($ret3:tt)*] $(= $fb3:expr)? ; )* }
     appended_caps { $( $(#[$acm:meta])* $acap:ident {
         $( $(#[$m4:meta])* $temp4:ident $name4:ident ( $recv4:tt $(, ($a4:ident : $($t4:tt)*))* )
            -> $form4:ident [$($ret4:tt)*] $(= $fb4:expr)? ; )* } )* }
    ) => {
        impl $live {
            $( $crate::__caller!{ bare [$(#[$m])*] $temp $name ( $recv $(, ($a : $($t)*))* ) -> $form [$($ret)*] } )*
            $( $( $crate::__caller!{ opt [$(#[$m2])*] $temp2 $name2 ( $recv2 $(, ($a2 : $($t2)*))* ) -> $form2 [$($ret2)*] } )* )*
            $( $crate::__caller!{ opt [$(#[$m3])*] $temp3 $name3 ( $recv3 $(, ($a3 : $($t3)*))* ) -> $form3 [$($ret3)*] } )*
            $( $( $crate::__caller!{ opt [$(#[$m4])*] $temp4 $name4 ( $recv4 $(, ($a4 : $($t4)*))* ) -> $form4 [$($ret4)*] } )* )*
            $(
                $(#[$fm])*
                pub fn $flag(&self) -> bool {
                    self.raw_class().$flag()
                }
            )*
        }
    };
}

/// One safe caller, by how the entry is typed in its record (`bare`: always
/// there; `opt`: a capability or an appended entry, `None` when absent) and
/// by calling convention.
#[doc(hidden)]
#[macro_export]
macro_rules! __caller {
    // ---- always there
    (bare [$($d:tt)*] hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> plain [$($ret:tt)*]) => {
        $($d)*
        #[inline]
        pub fn $name(&self, ctx: &mut $crate::abi::TraceCtx $(, $a: $crate::__safe_ty!($($t)*))*) -> $($ret)* {
            // SAFETY: a live handle vouches that the object is alive while
            // it exists; every pointer passed comes from a reference.
            unsafe { (self.raw_class().$name())(self.raw_this(), ctx $(, $crate::__to_raw!($a : $($t)*))*) }
        }
    };
    (bare [$($d:tt)*] hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        $($d)*
        #[inline]
        pub fn $name(&self, ctx: &mut $crate::abi::TraceCtx $(, $a: $crate::__safe_ty!($($t)*))*) {
            // SAFETY: as for every call through a live handle.
            unsafe { (self.raw_class().$name())(self.raw_this(), ctx $(, $crate::__to_raw!($a : $($t)*))*) }
        }
    };
    (bare [$($d:tt)*] hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> option [$($ret:tt)*]) => {
        $($d)*
        #[inline]
        pub fn $name(&self, ctx: &mut $crate::abi::TraceCtx $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<$($ret)*> {
            let mut out = ::std::mem::MaybeUninit::<$($ret)*>::uninit();
            // SAFETY: as for every call through a live handle; the entry
            // writes `out` when it returns true.
            unsafe {
                (self.raw_class().$name())(self.raw_this(), ctx $(, $crate::__to_raw!($a : $($t)*))*, out.as_mut_ptr())
                    .then(|| out.assume_init())
            }
        }
    };
    (bare [$($d:tt)*] pure $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> plain [$($ret:tt)*]) => {
        $($d)*
        #[inline]
        pub fn $name(&self $(, $a: $crate::__safe_ty!($($t)*))*) -> $($ret)* {
            // SAFETY: as for every call through a live handle.
            unsafe { (self.raw_class().$name())(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*) }
        }
    };
    (bare [$($d:tt)*] pure $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> option [$($ret:tt)*]) => {
        $($d)*
        #[inline]
        pub fn $name(&self $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<$($ret)*> {
            let mut out = ::std::mem::MaybeUninit::<$($ret)*>::uninit();
            // SAFETY: as for every call through a live handle; `out` is
            // written when the entry returns true.
            unsafe {
                (self.raw_class().$name())(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, out.as_mut_ptr())
                    .then(|| out.assume_init())
            }
        }
    };
    (bare [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> status []) => {
        $($d)*
        pub fn $name(&self $(, $a: $crate::__safe_ty!($($t)*))*) -> Result<(), $crate::sink::CallError> {
            let mut c = $crate::sink::Collected::default();
            // SAFETY: as for every call through a live handle; the sink
            // writes into `c`, which outlives the call.
            let st = unsafe { (self.raw_class().$name())(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, c.sink()) };
            c.result(st, stringify!($name), self.class_name())
        }
    };
    (bare [$($d:tt)*] cold $name:ident ( mut $(, ($a:ident : $($t:tt)*))* ) -> status []) => {
        $($d)*
        pub fn $name(&mut self $(, $a: $crate::__safe_ty!($($t)*))*) -> Result<(), $crate::sink::CallError> {
            let mut c = $crate::sink::Collected::default();
            // SAFETY: as for every call through a live handle; `&mut self`
            // is the exclusive access a `mut` entry needs.
            let st = unsafe { (self.raw_class().$name())(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, c.sink()) };
            c.result(st, stringify!($name), self.class_name())
        }
    };
    (bare [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        $crate::__caller!{ bare [$($d)*] cold $name ( const $(, ($a : $($t)*))* ) -> status [] }
    };
    (bare [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> value [$($ret:tt)*]) => {
        $($d)*
        pub fn $name(&self $(, $a: $crate::__safe_ty!($($t)*))*) -> Result<$($ret)*, $crate::sink::CallError> {
            let mut c = $crate::sink::Collected::default();
            let mut out = ::std::mem::MaybeUninit::<$($ret)*>::uninit();
            // SAFETY: as for every call through a live handle; on success
            // the entry wrote `out`.
            unsafe {
                let st = (self.raw_class().$name())(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, out.as_mut_ptr(), c.sink());
                c.result(st, stringify!($name), self.class_name())?;
                Ok(out.assume_init())
            }
        }
    };
    (bare [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> result [$($ret:tt)*]) => {
        $crate::__caller!{ bare [$($d)*] cold $name ( const $(, ($a : $($t)*))* ) -> value [$($ret)*] }
    };
    // ---- optional: `None` when the record lacks the entry
    (opt [$($d:tt)*] hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> plain [$($ret:tt)*]) => {
        $($d)*
        #[inline]
        // The caller takes the entry's arguments one for one.
        #[allow(clippy::too_many_arguments)]
        pub fn $name(&self, ctx: &mut $crate::abi::TraceCtx $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<$($ret)*> {
            let f = self.raw_class().$name()?;
            // SAFETY: as for every call through a live handle.
            Some(unsafe { f(self.raw_this(), ctx $(, $crate::__to_raw!($a : $($t)*))*) })
        }
    };
    (opt [$($d:tt)*] hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        $($d)*
        #[inline]
        // The caller takes the entry's arguments one for one.
        #[allow(clippy::too_many_arguments)]
        pub fn $name(&self, ctx: &mut $crate::abi::TraceCtx $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<()> {
            let f = self.raw_class().$name()?;
            // SAFETY: as for every call through a live handle.
            unsafe { f(self.raw_this(), ctx $(, $crate::__to_raw!($a : $($t)*))*) };
            Some(())
        }
    };
    (opt [$($d:tt)*] hot $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> option [$($ret:tt)*]) => {
        $($d)*
        #[inline]
        pub fn $name(&self, ctx: &mut $crate::abi::TraceCtx $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<$($ret)*> {
            let f = self.raw_class().$name()?;
            let mut out = ::std::mem::MaybeUninit::<$($ret)*>::uninit();
            // SAFETY: as for every call through a live handle; `out` is
            // written when the entry returns true.
            unsafe { f(self.raw_this(), ctx $(, $crate::__to_raw!($a : $($t)*))*, out.as_mut_ptr()).then(|| out.assume_init()) }
        }
    };
    (opt [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> status []) => {
        $($d)*
        pub fn $name(&self $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<Result<(), $crate::sink::CallError>> {
            let f = self.raw_class().$name()?;
            let mut c = $crate::sink::Collected::default();
            // SAFETY: as for every call through a live handle.
            let st = unsafe { f(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, c.sink()) };
            Some(c.result(st, stringify!($name), self.class_name()))
        }
    };
    (opt [$($d:tt)*] cold $name:ident ( mut $(, ($a:ident : $($t:tt)*))* ) -> status []) => {
        $($d)*
        pub fn $name(&mut self $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<Result<(), $crate::sink::CallError>> {
            let f = self.raw_class().$name()?;
            let mut c = $crate::sink::Collected::default();
            // SAFETY: as for every call through a live handle; `&mut self`
            // is the exclusive access a `mut` entry needs.
            let st = unsafe { f(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, c.sink()) };
            Some(c.result(st, stringify!($name), self.class_name()))
        }
    };
    (opt [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> unit []) => {
        $crate::__caller!{ opt [$($d)*] cold $name ( const $(, ($a : $($t)*))* ) -> status [] }
    };
    (opt [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> value [$($ret:tt)*]) => {
        $($d)*
        pub fn $name(&self $(, $a: $crate::__safe_ty!($($t)*))*) -> Option<Result<$($ret)*, $crate::sink::CallError>> {
            let f = self.raw_class().$name()?;
            let mut c = $crate::sink::Collected::default();
            let mut out = ::std::mem::MaybeUninit::<$($ret)*>::uninit();
            // SAFETY: as for every call through a live handle; on success
            // the entry wrote `out`.
            Some(unsafe {
                let st = f(self.raw_this() $(, $crate::__to_raw!($a : $($t)*))*, out.as_mut_ptr(), c.sink());
                c.result(st, stringify!($name), self.class_name()).map(|()| out.assume_init())
            })
        }
    };
    (opt [$($d:tt)*] cold $name:ident ( const $(, ($a:ident : $($t:tt)*))* ) -> result [$($ret:tt)*]) => {
        $crate::__caller!{ opt [$($d)*] cold $name ( const $(, ($a : $($t)*))* ) -> value [$($ret)*] }
    };
    // ---- constructors are called through the module, not a live object
    (opt [$($d:tt)*] ctor $name:ident ( new $(, ($a:ident : $($t:tt)*))* ) -> status []) => {};
    (bare [$($d:tt)*] ctor $name:ident ( new $(, ($a:ident : $($t:tt)*))* ) -> status []) => {};
}
