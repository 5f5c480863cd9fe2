// Types of tassel-three (web/src/index.js).
import type { Object3D } from 'three';

/** What GLTFLoader gives (`gltf.scene` and `gltf.parser.associations` are used). */
export interface GLTFLike {
  scene: Object3D;
  parser: { associations: Map<unknown, { nodes?: number }> };
}

export type TasselMode = 'fixed' | 'spec' | 'three-vrm' | 'classic' | 'kawaii' | 'spcr';

export interface TasselOptions {
  /** fixed (default), spec, three-vrm, classic, kawaii or spcr. */
  mode?: TasselMode;
  /** Where the .wasm is (URL), its bytes, or a compiled module; default: beside index.js. */
  wasm?: string | URL | ArrayBuffer | Uint8Array | WebAssembly.Module;
  /** Called with the message when an update fails (default: console.warn once). */
  onError?: (message: string) => void;
  /** Also keep the written bones' Euler `rotation` in step (costs more than the step). */
  syncRotation?: boolean;
  /** Refresh the written bones' `matrixWorld` in update (default true, as three-vrm does).
   *  false leaves it to the renderer's `scene.updateMatrixWorld()` (three.js runs it before
   *  every render): 12-30 % less time for a crowd of 100 characters (measured), but a
   *  bone's `matrixWorld` read between update and render is the last frame's. */
  worldMatrices?: boolean;
  /** Share the compiled rig with the other managers and characters made from the same
   *  bytes, rig and mode (default true: the file is parsed and compiled once, each copy
   *  only holds its own state; about 20 % less time a frame at 100 copies, measured).
   *  false loads this one on its own. Either way the results are the same, bit for bit. */
  shareRig?: boolean;
}

/** Loads the WebAssembly module once (done by fromGLTF too). */
export function loadTassel(source?: string | URL | ArrayBuffer | Uint8Array | WebAssembly.Module): Promise<unknown>;

/** What both classes share: one character stepped by Tassel. */
declare class Stepped {
  readonly mode: TasselMode;
  /** The three.js objects Tassel writes. */
  readonly bones: Object3D[];
  /** The last update's error (null when it stepped). */
  readonly lastError: string | null;
  update(delta: number): boolean;
  reset(): void;
  setInitState(): void;
  teleport(): void;
  /** Acts on an animation event starting with `tassel:` (`tassel:reset_dynamics`,
   *  `tassel:set_alpha 0.3 [chain]`, `tassel:enable_force NAME`, `tassel:disable_force NAME`,
   *  `tassel:force_once NAME`, `tassel:override NAME stiffness=0.5 duration=2 ...`,
   *  `tassel:stop_override NAME [blend_out]`): true when it acted, false for the game's
   *  own events; throws on a malformed one or a name that does not exist. */
  event(name: string): boolean;
  /** Starts a timed settings override of the rig's chains (KawaiiPhysics'
   *  StartPhysicsSettingsOverride): the scales (unset: 1) act on `chain` (unset: every
   *  chain) for `duration` seconds (Infinity: until stopped), blending in and out; up to 8
   *  at once, multiplying. Returns the handle; throws on a bad scale, time or chain. */
  startSettingsOverride(scale?: SettingsScale, options?: SettingsOverrideOptions): number;
  /** Stops a settings override by its handle over `blendOut` seconds (0: at once): true
   *  when one had the handle. */
  stopSettingsOverride(handle: number, blendOut?: number): boolean;
  /** This character's colliders in the world as its last update placed them (every
   *  collider, or the rig's `[[collider_group]]` named `group`), 12 floats each: kind (0
   *  sphere, 1 capsule, 2 tapered capsule, 3 box, 4 plane), four shape parameters, world
   *  translation x y z, rotation quaternion x y z w. */
  sharedColliders(group?: string | null): Float32Array;
  /** Sets the colliders other characters share with this one (as `sharedColliders` gives
   *  them): the chains with `use_shared_collision = true` collide with them. */
  setSharedColliders(floats: Float32Array | number[]): void;
  dispose(): void;
}

/** Multipliers of a chain's settings (1: no change). */
export interface SettingsScale {
  damping?: number;
  stiffness?: number;
  worldDampingLocation?: number;
  worldDampingRotation?: number;
  radius?: number;
  limitAngle?: number;
}

/** When a settings override acts: KawaiiPhysics' defaults 2 s, 0.2 s in, 0.5 s out. */
export interface SettingsOverrideOptions {
  duration?: number;
  blendIn?: number;
  blendOut?: number;
  chain?: string | null;
}

/** A drop-in for three-vrm's VRMSpringBoneManager, stepped by Tassel. */
/** Tassel's built-in character as a VRM 1.0 file (GLB bytes: a skinned body, 82 bones, 13
 *  VRM springs of 44 joints over 6 colliders), made by the module, free to redistribute. */
export function builtinAvatar(source?: string | URL | ArrayBuffer | Uint8Array | WebAssembly.Module): Promise<Uint8Array>;

export class TasselSpringBoneManager extends Stepped {
  static fromGLTF(gltf: GLTFLike, bytes: ArrayBuffer | Uint8Array, options?: TasselOptions & { rigToml?: string }): Promise<TasselSpringBoneManager>;
}

/** Any skinned glTF with a Tassel rig file, stepped by Tassel. */
export class TasselCharacter extends Stepped {
  static fromGLTF(gltf: GLTFLike, bytes: ArrayBuffer | Uint8Array, rigToml: string | null, options?: TasselOptions): Promise<TasselCharacter>;
}

/** Many characters of one file stepped together, one WebAssembly call a frame. */
export class TasselCrowd {
  static fromBytes(bytes: ArrayBuffer | Uint8Array, options?: TasselOptions & { rigToml?: string }): Promise<TasselCrowd>;
  readonly mode: TasselMode;
  /** 'vrm' or 'chains': side by side in SIMD lanes; 'characters': one after another. */
  readonly kind: 'vrm' | 'chains' | 'characters';
  readonly size: number;
  readonly members: TasselCrowdMember[];
  /** The last update's error (null when every member stepped). */
  readonly lastError: string | null;
  /** Adds a loaded copy of the file (its GLTFLoader result). */
  add(gltf: GLTFLike): TasselCrowdMember;
  /** Steps every member; false when some member's input was bad (those keep their pose). */
  update(delta: number): boolean;
  dispose(): void;
}

/** One character of a TasselCrowd; stands in for three-vrm's spring-bone manager (its
 *  update does nothing: the crowd's update steps it). */
export class TasselCrowdMember {
  readonly mode: TasselMode | null;
  readonly bones: Object3D[];
  readonly index: number;
  readonly lastError: string | null;
  update(delta?: number): boolean;
  reset(): void;
  setInitState(): void;
  teleport(): void;
  /** Leaves the crowd (the last member takes its place). */
  dispose(): void;
}
